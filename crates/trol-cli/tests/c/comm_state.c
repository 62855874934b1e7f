/*
 * Per-connection state in C (issue 38): two connections, a C500 through rapl: and a
 * simulated A465 on a pty. trol_strerror_for names each controller's BIOS codes as that
 * controller does; after the second controller dies (the test kills it when this program
 * says "stop b"), its connection's last communication error stays while another thread's
 * calls on the first connection succeed, and the first connection's stays 0; one error
 * handler installed on both tells which connection failed (trol_current, trol_get_user).
 * Driven by crates/trol-cli/tests/rapl.rs.
 */
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include "trol.h"

static TROL *a, *b;
static int a_failed = 0;
static const char *handler_saw = "nothing";

/* One ErrOnSend for both connections: it tells them apart by trol_current(). */
static TUINT on_send(SInData *in, TUINT *PCI)
{
    (void)in;
    (void)PCI;
    const char *who = trol_get_user(trol_current());
    handler_saw = who ? who : "(no user pointer)";
    return RECOVERY_FAIL;
}

static void *use_a(void *arg)
{
    (void)arg;
    for (int i = 0; i < 20; i++) {
        int last = 0;
        if (trol_get_status(a, &last) < 0)
            a_failed++;
        usleep(10000);
    }
    return NULL;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: comm_state RAPL_PORT SIM_PORT\n");
        return 2;
    }
    a = trol_connect(argv[1], 38400);
    b = trol_connect(argv[2], 38400);
    if (!a || !b) {
        printf("trol_connect: %s\n", trol_connect_error());
        return 1;
    }
    trol_set_user(a, "a");
    trol_set_user(b, "b");
    trol_set_err_on_send(a, on_send);
    trol_set_err_on_send(b, on_send);
    printf("a -9: %s\n", trol_strerror_for(a, -9));
    printf("b -9: %s\n", trol_strerror_for(b, -9));
    printf("b -1: %s\n", trol_strerror_for(b, -1));
    printf("stop b\n");
    fflush(stdout);
    char line[8];
    if (!fgets(line, sizeof line, stdin))
        return 1;
    int last = 0;
    int r = trol_get_status(b, &last);
    TUINT eb = trol_get_last_comm_err(b);
    TUINT side = trol_get_last_comm_side(b);
    pthread_t t;
    pthread_create(&t, NULL, use_a, NULL);
    TUINT changed = 0;
    for (int i = 0; i < 20; i++) {
        if (trol_get_last_comm_err(b) != eb)
            changed++;
        usleep(10000);
    }
    pthread_join(t, NULL);
    printf("b: %d, last comm error 0x%04x (side %u), changed %u times while a was used\n", r,
           (unsigned)eb, (unsigned)side, (unsigned)changed);
    printf("a: %d calls failed, last comm error 0x%04x\n", a_failed,
           (unsigned)trol_get_last_comm_err(a));
    printf("default connection: 0x%04x\n", (unsigned)GetLastCommErr());
    printf("the shared handler saw: %s\n", handler_saw);
    trol_disconnect(a);
    trol_disconnect(b);
    printf("done\n");
    return 0;
}
