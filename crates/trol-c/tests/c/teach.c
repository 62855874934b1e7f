/* Teaching from C (docs/teach.md): store where the arm is, define a precision point, list
 * the table, delete, move back to a taught location, save. Prints what it saw. */
#include <stdio.h>
#include <string.h>
#include "trol.h"

static void list(const char *when)
{
    TLocName names[8];
    SLocData locs[8];
    TUINT count = 0, i;
    TINT r = TROLListLocations(names, locs, 8, &count);
    printf("%s: %d, %u location(s):", when, r, count);
    for (i = 0; i < count && i < 8; i++) {
        char name[9];
        memcpy(name, names[i], 8);
        name[8] = 0;
        printf(" %s(tag %d)", name, locs[i].tag);
    }
    printf("\n");
}

int main(void)
{
    SLocData there, park, now;
    TUINT count = 0;
    float x = 420, y = -50, z = 330, pitch = 1.5707963f;
    memset(&there, 0, sizeof there);
    memset(&park, 0, sizeof park);
    memset(&now, 0, sizeof now);
    there.tag = POS_CART;
    there.numDims = 6;
    park.tag = POS_PREC;
    park.numDims = 6;
    now.tag = POS_CART;
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    there.data.cart[0] = x;
    there.data.cart[1] = y;
    there.data.cart[2] = z;
    there.data.cart[4] = pitch;
    TROLMoveII(&there, 0);
    TROLFinish(FINISH_WAIT);
    printf("here p1 -> %d\n", TROLHere((TUCHAR *)"p1", POS_CART));
    printf("here without # as prec -> %d\n", TROLHere((TUCHAR *)"pp", POS_PREC));
    park.data.prec[1] = 1000;
    printf("define #park -> %d\n", TROLDefine((TUCHAR *)"#park", &park));
    printf("count only -> %d\n", TROLListLocations(NULL, NULL, 0, &count));
    printf("count %u\n", count);
    printf("NULL count -> %d\n", TROLListLocations(NULL, NULL, 0, NULL));
    list("after teaching");
    printf("delete #park -> %d\n", TROLDeleteLocation((TUCHAR *)"#park"));
    printf("delete #park again -> %d\n", TROLDeleteLocation((TUCHAR *)"#park"));
    list("after deleting");
    TROLReady();
    TROLFinish(FINISH_WAIT);
    printf("move p1 -> %d\n", TROLMove((TUCHAR *)"p1", 0));
    TROLFinish(FINISH_WAIT);
    TROLGetPosition(&now, POS_COMMANDED);
    printf("at x %.1f y %.1f z %.1f\n", now.data.cart[0], now.data.cart[1], now.data.cart[2]);
    printf("save -> %d\n", TROLSaveLocations());
    CleanupTROL();
    return 0;
}
