/* A grasp checked from C (TROLGetGripper): closing on air holds nothing; closing at the
 * cube holds "cube" at its width. Prints what it saw. */
#include <stdio.h>
#include "trol.h"

static void show(const char *when)
{
    float opening = -1;
    TINT held = -1;
    char name[16] = "?";
    TINT r = TROLGetGripper(&opening, &held, name, sizeof name);
    printf("%s: %d, opening %.1f mm, held %d, name \"%s\"\n", when, r, opening, held, name);
}

int main(void)
{
    float opening;
    TINT held;
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    printf("NULL -> %d\n", TROLGetGripper(NULL, &held, NULL, 0));
    printf("name NULL with a size -> %d\n", TROLGetGripper(&opening, &held, NULL, 8));
    TROLClose(50);
    TROLFinish(FINISH_WAIT);
    show("on air");
    TROLOpen(100);
    TROLMove((TUCHAR *)"p2", 0);
    TROLFinish(FINISH_WAIT);
    TROLClose(50);
    TROLFinish(FINISH_WAIT);
    show("at the cube");
    CleanupTROL();
    return 0;
}
