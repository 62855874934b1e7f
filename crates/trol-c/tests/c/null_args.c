/*
 * NULL where the manual's layer functions write their results is refused at once, with
 * nothing sent or waited for (issue 38): ReceiveData(&out, NULL) waited 15 s for a message it
 * could not hand over; TransSR(NULL, ...) said only TRANS_ERR_SEND. The default connection
 * is the embedded simulator; the next call works. Driven by tests/c_callbacks.rs.
 */
#include <stdio.h>
#include <time.h>
#include "trol.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec / 1e9;
}

int main(void)
{
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    SOutData out;
    double t0 = now();
    TUINT r = ReceiveData(&out, NULL);
    printf("ReceiveData(&out, NULL) -> 0x%04x after %.1f s\n", (unsigned)r, now() - t0);
    SOutData resp;
    printf("TransSR(NULL, &resp) -> %u\n", (unsigned)TransSR(NULL, &resp));
    printf("TROLSpeed(50) -> %d\n", TROLSpeed(50));
    CleanupTROL();
    return 0;
}
