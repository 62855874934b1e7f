/* A call before InitTROL: TROL_ERR_COMM, and one line on stderr that says why (tests/c_callbacks.rs). */
#include <stdio.h>
#include "trol.h"
int main(void) { printf("%d\n", TROLHome(0)); printf("%d\n", TROLReady()); return 0; }
