/*
 * A 1998 program against a controller that freezes (issue 67, item 2): InitTROL(1) with the
 * manual's three-line trol.cfg (baud, port, tool) in the current directory, on a TROL server
 * started active; after "go" on stdin (the test has frozen the controller by then) one
 * TROLGetPosition, timed. Prints "ready", then "position RET MS". Driven by
 * crates/trol-cli/tests/faults.rs.
 */
#include <stdio.h>
#include <time.h>
#include "trol.h"

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000.0 + t.tv_nsec / 1e6;
}

int main(void)
{
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    SLocData here;
    here.tag = POS_JOINT;
    if (TROLGetPosition(&here, POS_ACT) != 0) {
        printf("the first GetPosition failed\n");
        return 1;
    }
    printf("ready\n");
    fflush(stdout);
    char line[16];
    if (!fgets(line, sizeof line, stdin)) {
        return 1;
    }
    double t = now_ms();
    here.tag = POS_JOINT;
    int ret = TROLGetPosition(&here, POS_ACT);
    printf("position %d %.0f\n", ret, now_ms() - t);
    fflush(stdout);
    return 0;
}
