/* TROLFinish(FINISH_WAIT) is bounded as the manual's one long request was: after the reply
 * timeout (SetL3_TO_Intervall) the application's ErrAppTimeOut decides. RECOVERY_FAIL ends
 * the wait with TROL_ERR_COMM; RECOVERY_SUCCESS waits one more reply timeout, and asks
 * again. Prints what it saw. */
#include <stdio.h>
#include "trol.h"

static int calls = 0;
static TUINT answer = RECOVERY_FAIL;

TUINT ErrAppTimeOut(SInData *in)
{
    calls++;
    printf("ErrAppTimeOut: command %d\n", in->numBytes > 0 ? in->data[0] : -1);
    return answer;
}

int main(void)
{
    TINT r;
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    SetL3_TO_Intervall(10); /* 1 s */
    TROLSpeed(10);
    /* A motion of some seconds; the handler gives up after the first second. */
    r = TROLJoint(1, 2.0);
    printf("TROLJoint -> %d\n", r);
    r = TROLFinish(FINISH_WAIT);
    printf("gave up: TROLFinish -> %d after %d call(s)\n", r, calls);
    TROLHalt();
    TROLFinish(FINISH_WAIT);
    /* Now it grants more each time: the wait ends with the motion. */
    answer = RECOVERY_SUCCESS;
    calls = 0;
    r = TROLJoint(1, -2.0);
    r = TROLFinish(FINISH_WAIT);
    printf("waited: TROLFinish -> %d after %d call(s)\n", r, calls);
    CleanupTROL();
    return 0;
}
