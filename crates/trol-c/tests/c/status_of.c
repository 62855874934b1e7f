/*
 * The manual's GetStatus method with the additions that make it exact: after a call, the
 * number of its request (TROLLastTransaction) and the status's own (TROLGetStatusOf).
 * Driven by tests/c_callbacks.rs against the embedded simulator.
 */
#include <stdio.h>
#include "trol.h"

int main(void)
{
    int last = 0;
    TUINT t = 0, e = 0, n;
    TINT r, called;

    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    /* Refused by the arm (not homed): the status is this call's, and says so. */
    r = TROLJoint(1, 0.1f);
    n = TROLLastTransaction();
    called = TROLGetStatusOf(&last, &t, &e);
    printf("TROLJoint -> %d; request %u; status of %u: called %d, last %d; epoch %s\n", r, n, t,
           called, last, e ? "set" : "0");
    /* After Home, the same method on a call that ran. */
    TROLHome(0);
    r = TROLJoint(1, 0.1f);
    n = TROLLastTransaction();
    called = TROLGetStatusOf(&last, NULL, NULL);
    TROLGetStatusOf(&last, &t, NULL);
    printf("TROLJoint -> %d; request %u; later status of %u: called %d, last %d\n", r, n, t,
           called, last);
    printf("NULL -> %d\n", TROLGetStatusOf(NULL, &t, &e));
    CleanupTROL();
    return 0;
}
