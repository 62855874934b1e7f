/*
 * TROLHalt from a second thread while the first waits in TROLFinish(FINISH_WAIT): the wait
 * polls with the library's lock free between polls, so the Halt gets through.
 */
#include <pthread.h>
#include <stdio.h>
#include <time.h>
#include <unistd.h>
#include "trol.h"

static void *halter(void *arg)
{
    (void)arg;
    usleep(500 * 1000);
    printf("TROLHalt -> %d\n", TROLHalt());
    return NULL;
}

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec / 1e9;
}

int main(void)
{
    pthread_t thread;
    SLocData pos;
    double start;
    if (InitTROL(1) != INITTROL_SUCCESS)
        return 1;
    TROLSpeed(10);
    printf("TROLJoint -> %d\n", TROLJoint(1, 2.0f)); /* over 6 s at 10 % */
    pthread_create(&thread, NULL, halter, NULL);
    start = seconds();
    printf("TROLFinish -> %d\n", TROLFinish(FINISH_WAIT));
    printf("waited %.1f s\n", seconds() - start);
    pthread_join(thread, NULL);
    pos.tag = POS_JOINT;
    TROLGetPosition(&pos, POS_COMMANDED);
    printf("j1 %.3f\n", pos.data.joint[0]);
    return 0;
}
