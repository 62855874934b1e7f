/*
 * Two arms in one process, each driven from its own thread through trol_connect, and an
 * error handler that calls TROL: on its own connection it gets TROL_ERR_COMM at once (no
 * deadlock), the other connection works. Driven by tests/c_callbacks.rs, which starts two
 * `trol sim` processes and names their ports on the command line; it kills the first before
 * the handler step, when this program says so.
 */
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include "trol.h"

struct job {
    TROL *c;
    float j1;
    int result;
    float seen;
};

static void *drive(void *arg)
{
    struct job *j = arg;
    SLocData q;
    memset(&q, 0, sizeof q);
    q.tag = POS_JOINT;
    q.numDims = 6;
    q.data.joint[0] = j->j1;
    q.data.joint[2] = 0.5f;
    j->result = trol_ma(j->c, &q);
    if (j->result == 0)
        j->result = trol_finish(j->c, FINISH_WAIT);
    SLocData at;
    at.tag = POS_JOINT;
    if (j->result == 0)
        j->result = trol_get_position(j->c, &at, POS_COMMANDED);
    j->seen = at.data.joint[0];
    return NULL;
}

static TROL *arms[2];
static int own = 1, other = 1;

static TUINT on_send(SInData *in, TUINT *PCI)
{
    int last = 0;
    (void)in;
    (void)PCI;
    own = trol_get_status(arms[0], &last);   /* its own connection: busy */
    other = trol_get_status(arms[1], &last); /* the other works */
    return RECOVERY_FAIL;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: two_arms PORT_A PORT_B\n");
        return 2;
    }
    if (trol_connect(NULL, 9600) != NULL || strstr(trol_connect_error(), "NULL") == NULL) {
        printf("NULL port not refused\n");
        return 1;
    }
    for (int i = 0; i < 2; i++) {
        arms[i] = trol_connect(argv[1 + i], 38400);
        if (!arms[i]) {
            printf("trol_connect(%s): %s\n", argv[1 + i], trol_connect_error());
            return 1;
        }
        trol_home(arms[i], 0);
    }
    struct job jobs[2] = {{arms[0], 0.4f, -1, 0}, {arms[1], -0.7f, -1, 0}};
    pthread_t t[2];
    for (int i = 0; i < 2; i++)
        pthread_create(&t[i], NULL, drive, &jobs[i]);
    for (int i = 0; i < 2; i++)
        pthread_join(t[i], NULL);
    for (int i = 0; i < 2; i++)
        printf("arm %d: %d, joint 1 at %.3f\n", i, jobs[i].result, jobs[i].seen);
    printf("strerror(-1): %s\n", trol_strerror(-1));
    printf("strerror(-32102): %s\n", trol_strerror(-32102));
    printf("NULL handle: %d\n", trol_halt(NULL));

    /* The first controller goes away; its handler calls TROL. */
    trol_set_err_on_send(arms[0], on_send);
    printf("kill the first\n");
    fflush(stdout);
    char line[16];
    if (!fgets(line, sizeof line, stdin))
        return 1;
    printf("halt on the dead one: %d\n", trol_halt(arms[0]));
    printf("in its handler: own %d, other %d\n", own, other);
    trol_disconnect(arms[0]);
    trol_disconnect(arms[1]);
    printf("done\n");
    return 0;
}
