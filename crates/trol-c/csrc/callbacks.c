/*
 * The manual's error handlers under their own names ("Callback-Routinen"): an application
 * that defines ErrOnSend, ErrOnReceive, ErrAppTimeOut or FatalError gets it called, as with
 * the manual's callback.c. libtrol refers to them weakly: defined by the application, the
 * reference resolves to its function (with libtrol.so at load time, with libtrol.a at link
 * time); not defined, it is NULL and TROL's default runs.
 */
#include <stdint.h>

typedef struct { uint16_t numBytes; uint8_t *data; } SInData;

extern uint16_t ErrOnSend(SInData *in, uint16_t *PCI) __attribute__((weak));
extern uint16_t ErrOnReceive(SInData *out, uint16_t *PCI) __attribute__((weak));
extern uint16_t ErrAppTimeOut(SInData *in) __attribute__((weak));
extern int16_t FatalError(uint16_t command, int16_t errorCode) __attribute__((weak));

void *trol_weak_err_on_send(void) { return (void *)ErrOnSend; }
void *trol_weak_err_on_receive(void) { return (void *)ErrOnReceive; }
void *trol_weak_err_app_timeout(void) { return (void *)ErrAppTimeOut; }
void *trol_weak_fatal_error(void) { return (void *)FatalError; }
