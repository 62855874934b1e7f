/* An added API function written the manual's way (3.6.4): it ends in FatalError, and the
 * program defines no FatalError of its own. It links (libtrol has a default) and the
 * default returns the error code. */
#include <stdio.h>
#include "trol.h"

static TINT MyMoveNowhere(void)
{
    TINT r = TROLMove("nowhere", 0);
    return r < 0 ? FatalError(TROL_MOVE, r) : r;
}

int main(void)
{
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    printf("FatalError(TROL_MOVE, -5) -> %d\n", FatalError(TROL_MOVE, -5));
    printf("MyMoveNowhere -> %d\n", MyMoveNowhere());
    CleanupTROL();
    return 0;
}
