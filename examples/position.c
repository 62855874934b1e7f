/* Read the position in all three forms, commanded and actual, and use GetStatus. */
#include <stdio.h>
#include "trol.h"

static void show(const char *name, SLocData *p)
{
    int i;
    printf("%-6s", name);
    for (i = 0; i < p->numDims; i++) {
        if (p->tag == POS_PREC) printf(" %9ld", (long)p->data.prec[i]);
        else printf(" %9.4f", p->data.cart[i]);
    }
    printf("\n");
}

int main(void)
{
    SLocData pos;
    int last = 0;
    TINT called, r;
    int bad = 0;
    TUCCHAR nowhere[] = "nowhere"; /* a location's name is TUCCHAR in the manual's API */

    if (InitTROL(1) != INITTROL_SUCCESS) {
        fprintf(stderr, "InitTROL failed\n");
        return 1;
    }
    TROLHome(0);
    r = TROLJoint(1, 0.5f);
    TROLFinish(FINISH_WAIT);
    called = TROLGetStatus(&last);
    printf("TROLJoint(1, 0.5) -> %d; GetStatus: BIOS called %d, returned %d\n", r, called, last);
    bad |= (r != 0 || called != 1 || last != 0);

    pos.tag = POS_CART;  bad |= TROLGetPosition(&pos, POS_COMMANDED) != 0; show("cart", &pos);
    pos.tag = POS_JOINT; bad |= TROLGetPosition(&pos, POS_COMMANDED) != 0; show("joint", &pos);
    bad |= (pos.numDims != 6 || pos.data.joint[0] < 0.49f || pos.data.joint[0] > 0.51f);
    pos.tag = POS_PREC;  bad |= TROLGetPosition(&pos, POS_ACT) != 0;       show("prec", &pos);

    r = TROLMove(nowhere, 0);
    called = TROLGetStatus(&last);
    printf("TROLMove(nowhere) -> %d; GetStatus: BIOS called %d, reason %d\n", r, called, last);
    bad |= (r != TROL_ERR_LOCATION || called != 0 || last != TROL_ERR_LOCATION);

    CleanupTROL();
    printf(bad ? "position: FAILED\n" : "position: done\n");
    return bad;
}
