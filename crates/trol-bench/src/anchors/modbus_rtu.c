/* The libmodbus anchor of `trol bench pty`: Modbus RTU round trips over a pty pair between
 * two processes, as TROL's transactions over a pty run between `trol sim` and the bench.
 *
 * A child process serves slave 1 on the pty's slave end; the parent writes one holding
 * register per round trip (function 6: 8 bytes each way, a small write as TROLSpeed is) on
 * the master end. libmodbus does its own I/O on the descriptors (modbus_set_socket: no
 * device path to open, no termios of its own). Prints the microseconds per round trip.
 *
 * With two device paths (`trol bench relay`: the two ends of a paced relay process), the
 * child serves on SERVER_DEV and the parent asks on CLIENT_DEV instead of a pty pair of its
 * own.
 *
 * Build: cc -O2 -o modbus_rtu modbus_rtu.c $(pkg-config --cflags --libs libmodbus) -lutil
 * Run:   ./modbus_rtu COUNT [SERVER_DEV CLIENT_DEV]
 */
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <pty.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

static int raw(int fd) {
    struct termios t;
    if (tcgetattr(fd, &t) != 0)
        return -1;
    cfmakeraw(&t);
    return tcsetattr(fd, TCSANOW, &t);
}

static modbus_t *rtu(int fd) {
    /* The device name is never opened: the descriptor is set instead. */
    modbus_t *ctx = modbus_new_rtu("/dev/null", 38400, 'N', 8, 1);
    if (ctx == NULL)
        return NULL;
    modbus_set_slave(ctx, 1);
    modbus_set_socket(ctx, fd);
    return ctx;
}

static void serve(int fd) {
    modbus_t *ctx = rtu(fd);
    modbus_mapping_t *map = modbus_mapping_new(0, 0, 16, 0);
    uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
    if (ctx == NULL || map == NULL)
        _exit(2);
    for (;;) {
        int n = modbus_receive(ctx, query);
        if (n > 0)
            modbus_reply(ctx, query, n, map);
        else if (n == -1 && errno != EMBBADCRC && errno != EMBBADDATA)
            _exit(0);
    }
}

int main(int argc, char **argv) {
    long count = argc > 1 ? atol(argv[1]) : 1000;
    int master = -1, slave = -1;
    if (argc == 4) {
        /* The relay's ends: opened here (the client's) and in the child (the server's). */
        master = open(argv[3], O_RDWR | O_NOCTTY);
        if (master < 0 || raw(master) != 0) {
            fprintf(stderr, "modbus_rtu: cannot open %s: %s\n", argv[3], strerror(errno));
            return 2;
        }
    } else if (count < 1 || openpty(&master, &slave, NULL, NULL, NULL) != 0 || raw(slave) != 0) {
        fprintf(stderr, "modbus_rtu: usage: modbus_rtu COUNT [SERVER_DEV CLIENT_DEV]\n");
        return 2;
    }
    if (count < 1)
        return 2;
    pid_t child = fork();
    if (child < 0)
        return 2;
    if (child == 0) {
        close(master);
        if (argc == 4) {
            slave = open(argv[2], O_RDWR | O_NOCTTY);
            if (slave < 0 || raw(slave) != 0)
                _exit(2);
        }
        serve(slave);
    }
    if (slave >= 0)
        close(slave);
    modbus_t *ctx = rtu(master);
    if (ctx == NULL)
        return 2;
    modbus_set_response_timeout(ctx, 2, 0);
    /* Warm up: the first round trips pay for the pages and the scheduler's first moves. */
    for (int i = 0; i < 50; i++) {
        if (modbus_write_register(ctx, 0, i) != 1) {
            fprintf(stderr, "modbus_rtu: %s\n", modbus_strerror(errno));
            return 1;
        }
    }
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (long i = 0; i < count; i++) {
        if (modbus_write_register(ctx, 1, (uint16_t)i) != 1) {
            fprintf(stderr, "modbus_rtu: %s\n", modbus_strerror(errno));
            return 1;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    double us = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / 1e3 / count;
    printf("%.3f\n", us);
    kill(child, SIGTERM);
    waitpid(child, NULL, 0);
    modbus_free(ctx);
    return 0;
}
