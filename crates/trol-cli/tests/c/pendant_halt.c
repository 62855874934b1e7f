/*
 * A Halt from the pendant is seen by the program (issue 37): this program starts a long
 * joint motion on the controller named by argv[1] and waits for it with the manual's
 * TROLFinish(FINISH_WAIT), one request that the controller answers at the motion's end. The
 * test halts the arm through the browser's pendant meanwhile; Finish must then answer
 * TROL_ERR_HALTED, and GetStatus say so. Driven by crates/trol-cli/tests/view.rs.
 */
#include <stdio.h>
#include "trol.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: pendant_halt PORT\n");
        return 2;
    }
    TROL *r = trol_connect(argv[1], 38400);
    if (!r) {
        printf("trol_connect: %s\n", trol_connect_error());
        return 1;
    }
    if (trol_speed(r, 10) != 0 || trol_joint(r, 1, 2.0f) != 0) {
        printf("the motion was not started\n");
        return 1;
    }
    printf("moving\n");
    fflush(stdout);
    int f = trol_finish(r, FINISH_WAIT);
    printf("finish %d: %s\n", f, trol_strerror_for(r, f));
    int last = 0;
    trol_get_status(r, &last);
    printf("status %d\n", last);
    /* Once: the next Finish is the ordinary one. */
    printf("again %d\n", trol_finish(r, FINISH_WAIT));
    trol_disconnect(r);
    return 0;
}
