/* A 1998-style TROL program that carries on after its controller restarts: it moves,
 * waits for a line on stdin (the test restarts the controller meanwhile), then goes on
 * calling until a call succeeds again (at most 50 tries, 100 ms apart). */
#include <stdio.h>
#include <time.h>
#include "trol.h"

int main(void)
{
    char line[16];
    struct timespec pause = {0, 100 * 1000 * 1000};
    int r, tries = 0;
    if (InitTROL(1) != INITTROL_SUCCESS) {
        printf("InitTROL failed\n");
        return 1;
    }
    printf("first %d\n", TROLJoint(1, 0.1f));
    fflush(stdout);
    if (!fgets(line, sizeof line, stdin))
        return 1;
    while ((r = TROLJoint(1, 0.1f)) != 0 && tries < 50) {
        printf("while restarting %d, GetLastCommErr 0x%04x\n", r, GetLastCommErr());
        tries++;
        nanosleep(&pause, NULL);
    }
    printf("after %d tries: %d\n", tries, r);
    return r == 0 ? 0 : 1;
}
