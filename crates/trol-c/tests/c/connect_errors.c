/* trol_connect's failures, typed: a port that cannot be opened, and a controller (argv[1])
 * that speaks another protocol version, with both version numbers. Prints what it saw;
 * exits 0 when each failure came with its kind. */
#include <stdio.h>
#include <string.h>
#include "trol.h"

int main(int argc, char **argv)
{
    TUINT ours = 99, theirs = 99;
    int failed = 0;
    if (argc < 2) {
        fprintf(stderr, "usage: connect_errors PORT-OF-AN-OLD-CONTROLLER\n");
        return 2;
    }
    if (trol_connect("/nonexistent/trol-port", 9600) != NULL) {
        printf("connected to a port that does not exist\n");
        return 1;
    }
    printf("no port: kind %d: %s\n", trol_connect_error_kind(), trol_connect_error());
    failed |= trol_connect_error_kind() != TROL_SETUP_PORT;

    if (trol_connect(argv[1], 9600) != NULL) {
        printf("connected to a controller of another version\n");
        return 1;
    }
    trol_connect_versions(&ours, &theirs);
    printf("old controller: kind %d, ours %u, theirs %u: %s\n", trol_connect_error_kind(),
           (unsigned)ours, (unsigned)theirs, trol_connect_error());
    failed |= trol_connect_error_kind() != TROL_SETUP_INCOMPATIBLE;
    failed |= ours != TROL_PROTOCOL_VERSION || theirs != 2;

    /* A success clears the kind. */
    {
        TROL *sim = trol_connect("sim", 9600);
        if (sim == NULL) {
            printf("sim: %s\n", trol_connect_error());
            return 1;
        }
        failed |= trol_connect_error_kind() != TROL_SETUP_NONE;
        failed |= strlen(trol_connect_error()) != 0;
        trol_disconnect(sim);
    }
    return failed;
}
