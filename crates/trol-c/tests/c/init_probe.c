/* InitTROL(0) against a controller in terminal mode: it probes for a server (none answers),
 * activates one, and checks it; the application's handlers are not called for those probes,
 * which are InitTROL's own, not the application's calls. Exits 0 when no handler was called
 * and the call after InitTROL works. */
#include <stdio.h>
#include "trol.h"

static int calls = 0;

TUINT ErrOnSend(SInData *in, TUINT *PCI)
{
    (void)in;
    (void)PCI;
    calls++;
    return RECOVERY_FAIL;
}

TUINT ErrOnReceive(SOutData *out, TUINT *PCI)
{
    (void)out;
    (void)PCI;
    calls++;
    return RECOVERY_FAIL;
}

int main(void)
{
    TINT r;
    if (InitTROL(0) != INITTROL_SUCCESS) {
        printf("InitTROL(0) failed\n");
        return 1;
    }
    printf("handler calls during InitTROL(0): %d\n", calls);
    r = TROLSpeed(50);
    printf("TROLSpeed -> %d\n", r);
    CleanupTROL();
    return calls != 0 || r != 0;
}
