/*
 * The manual's error handlers defined under their own names, with no TROLSet* call: each
 * counts its calls, and ErrOnReceive receives the reply itself, as the manual describes.
 * Driven by tests/c_callbacks.rs, whose scripted controller provokes each failure.
 */
#include <stdio.h>
#include "trol.h"

static int sends, receives, timeouts, fatals;
static int buffer_was_empty = -1;

TUINT ErrOnSend(SInData *in, TUINT *PCI)
{
    (void)PCI;
    sends++;
    printf("ErrOnSend: %u bytes, command %u, GetLastCommErr 0x%04x, side %u\n", in->numBytes,
           in->numBytes ? in->data[0] : 0, GetLastCommErr(), GetLastCommSide());
    return RECOVERY_FAIL;
}

TUINT ErrOnReceive(SOutData *out, TUINT *PCI)
{
    receives++;
    printf("ErrOnReceive: GetLastCommErr 0x%04x, side %u\n", GetLastCommErr(),
           GetLastCommSide());
    /* Receive the reply ourselves and hand it on. */
    if (ReceiveData(out, PCI) == 0) {
        printf("ErrOnReceive: received %u bytes\n", out->numBytes);
        return RECOVERY_SUCCESS;
    }
    return RECOVERY_FAIL;
}

TUINT ErrAppTimeOut(SInData *in)
{
    timeouts++;
    if (buffer_was_empty < 0)
        buffer_was_empty = BufferEmpty();
    printf("ErrAppTimeOut: command %u\n", in->data[0]);
    return timeouts < 20 ? RECOVERY_SUCCESS : RECOVERY_FAIL;
}

TINT FatalError(TUINT command, TINT errorCode)
{
    fatals++;
    printf("FatalError: command %u, code %d\n", command, errorCode);
    return errorCode;
}

int main(void)
{
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    /* 1: the controller does not answer ENQ: ErrOnSend, then FatalError(TROL_ERR_COMM). */
    printf("TROLHalt -> %d\n", TROLHalt());
    /* 2: the reply starts with garbage: ErrOnReceive receives it itself. */
    printf("TROLReady -> %d\n", TROLReady());
    /* 3: the reply comes late: ErrAppTimeOut is asked and waits on. */
    SetL3_TO_Intervall(2);
    printf("TROLGrip -> %d\n", TROLGrip(10));
    SetL3_TO_Intervall(150);
    /* 4: the controller refuses: FatalError(TROL_MOVE, TROL_ERR_LOCATION). */
    printf("TROLMove -> %d\n", TROLMove("nowhere", 0));
    /* 5: the reply starts with garbage and never comes: ErrOnReceive's RECOVERY_FAIL ends
     * the call; the request is not sent again (the controller checks). */
    printf("TROLOpen -> %d\n", TROLOpen(50));
    printf("after TROLOpen: GetLastCommErr 0x%04x\n", GetLastCommErr());
    /* 6: a call refused before it reaches the line: GetLastCommErr speaks of it, 0. */
    {
        TINT r = TROLSpeed(0);
        printf("TROLSpeed(0) -> %d, GetLastCommErr 0x%04x\n", r, GetLastCommErr());
    }
    printf("calls: send %d receive %d timeout %d fatal %d; buffer empty at first timeout %d\n",
           sends, receives, timeouts, fatals, buffer_was_empty);
    return 0;
}
