/* A trajectory from C (docs/protocol.md "Trajectory"): timed on the simulated A465, the
 * arm at the last waypoint after TROLFinish; what the library can check is refused before
 * anything is sent; a trajectory faster than the arm is the controller's BIOS_TOO_FAST.
 * Prints what it saw. */
#include <stdio.h>
#include <string.h>
#include "trol.h"

int main(void)
{
    STrajPoint path[2];
    STrajPoint fast[1];
    SLocData now;
    int i;
    memset(path, 0, sizeof path);
    memset(fast, 0, sizeof fast);
    memset(&now, 0, sizeof now);
    path[0].time = 1.0f;
    path[0].joints[0] = 0.3f;
    path[0].joints[2] = 0.5f;
    path[1].time = 2.0f;
    path[1].joints[0] = 0.5f;
    path[1].joints[1] = 0.25f;
    path[1].joints[2] = 0.75f;
    fast[0].time = 0.05f;
    fast[0].joints[0] = -1.0f;
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    printf("trajectory -> %d\n", TROLTrajectory(path, 2));
    printf("finish -> %d\n", TROLFinish(FINISH_WAIT));
    now.tag = POS_JOINT;
    TROLGetPosition(&now, POS_COMMANDED);
    printf("at");
    for (i = 0; i < 6; i++) {
        printf(" %.3f", now.data.joint[i]);
    }
    printf("\n");
    printf("NULL points -> %d\n", TROLTrajectory(NULL, 2));
    printf("no points -> %d\n", TROLTrajectory(path, 0));
    path[1].time = 0.5f;
    printf("times back -> %d\n", TROLTrajectory(path, 2));
    printf("too fast -> %d\n", TROLTrajectory(fast, 1));
    printf("no connection -> %d\n", trol_trajectory(NULL, path, 2));
    CleanupTROL();
    return 0;
}
