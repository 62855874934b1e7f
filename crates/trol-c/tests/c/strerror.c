/* trol_strerror names a BIOS code as the controller InitTROL connected to names it (its codes
 * come with the version check, TROLGetCodes); before InitTROL, by the default table. */
#include <stdio.h>
#include "trol.h"

int main(void)
{
    printf("before: %s\n", trol_strerror(-77));
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    printf("after: %s\n", trol_strerror(-77));
    printf("TROL's own: %s\n", trol_strerror(TROL_ERR_LOCATION));
    CleanupTROL();
    return 0;
}
