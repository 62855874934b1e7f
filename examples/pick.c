/* The manual's pick example (TROLAppro): approach test_001 along the tool x axis, move onto
 * it, close the gripper, depart. delay() is replaced by a portable sleep. */
#include <stdio.h>
#include <time.h>
#include "trol.h"

static void sleep_ms(long ms)
{
    struct timespec t = { ms / 1000, (ms % 1000) * 1000000L };
    nanosleep(&t, NULL);
}

static int check(const char *what, TINT r)
{
    printf("%-28s -> %d\n", what, r);
    return r != 0;
}

int main(void)
{
    /* A location's name is TUCCHAR (unsigned char) in the manual's API: an array of it
     * takes the name without a cast. */
    TUCCHAR test_001[] = "test_001";
    SLocData loc;
    int bad = 0;

    if (InitTROL(1) != INITTROL_SUCCESS) {
        fprintf(stderr, "InitTROL failed\n");
        return 1;
    }
    bad |= check("TROLHome(0)", TROLHome(0));
    bad |= check("TROLFinish(FINISH_WAIT)", TROLFinish(FINISH_WAIT));

    loc.tag = POS_CART; loc.data.cart[0] = -90.0;
    loc.numDims = 1;
    bad |= check("TROLAppro(test_001, -90, 0)", TROLAppro(test_001, &loc, 0));
        /* from READY (tool up) get above the object joint-interpolated first: a straight
         * line from there would turn the tool through the joint limits */

    /* The manual's example: */
    bad |= check("TROLAppro(test_001, -90, 1)", TROLAppro(test_001, &loc, 1));
        /* approach along the tool x axis to 9 cm, in a straight line */
    bad |= check("TROLMove(test_001, 1)", TROLMove(test_001, 1));
        /* move the TCP straight onto the object */
    bad |= check("TROLFinish(FINISH_WAIT)", TROLFinish(FINISH_WAIT));
        /* wait until the motion is done */
    bad |= check("TROLClose(60)", TROLClose(60));
        /* grip the object */
    sleep_ms(2000 / 20);
        /* wait until the gripper is closed (the simulation runs 20 times faster) */
    bad |= check("TROLFinish(FINISH_WAIT)", TROLFinish(FINISH_WAIT));
    bad |= check("TROLDepart(&loc, 1)", TROLDepart(&loc, 1));
        /* back 9 cm along the tool x axis */
    bad |= check("TROLFinish(FINISH_WAIT)", TROLFinish(FINISH_WAIT));
    CleanupTROL();
    printf(bad ? "pick: FAILED\n" : "pick: done\n");
    return bad;
}
