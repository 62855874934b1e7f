/* A call before InitTROL: TROL_ERR_NOT_INIT (told apart from a failed line, TROL_ERR_COMM),
 * and one line on stderr that says why (tests/c_callbacks.rs). */
#include <stdio.h>
#include "trol.h"
int main(void)
{
    printf("%d\n", TROLHome(0));
    printf("%d\n", TROLReady());
    printf("%d: %s\n", TROL_ERR_NOT_INIT, trol_strerror(TROL_ERR_NOT_INIT));
    return 0;
}
