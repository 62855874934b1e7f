/*
 * The manual's error handlers under their own names ("Callback-Routinen"): an application
 * that defines ErrOnSend, ErrOnReceive, ErrAppTimeOut or FatalError gets it called, as with
 * the manual's callback.c. libtrol refers to them weakly: defined by the application, the
 * reference resolves to its function (with libtrol.so at load time, with libtrol.a at link
 * time); not defined, it is NULL (FatalError: the default below) and TROL's default runs.
 */
#include <stdint.h>

typedef struct { uint16_t numBytes; uint8_t *data; } SInData;

extern uint16_t ErrOnSend(SInData *in, uint16_t *PCI) __attribute__((weak));
extern uint16_t ErrOnReceive(SInData *out, uint16_t *PCI) __attribute__((weak));
extern uint16_t ErrAppTimeOut(SInData *in) __attribute__((weak));

/* FatalError also has a default definition, weak, so that code written the manual's way (an
 * added API function that calls FatalError, manual 3.6.4) links without one of its own: it
 * returns the error code, TROL's default. An application's own definition takes its place
 * (libtrol.so exports the default, csrc/exports.map, and the program's definition comes
 * first; with libtrol.a the program's strong definition wins over the weak one). */
int16_t trol_default_fatal_error(uint16_t command, int16_t errorCode)
{
    (void)command;
    return errorCode;
}
int16_t FatalError(uint16_t command, int16_t errorCode)
    __attribute__((weak, alias("trol_default_fatal_error")));

void *trol_weak_err_on_send(void) { return (void *)ErrOnSend; }
void *trol_weak_err_on_receive(void) { return (void *)ErrOnReceive; }
void *trol_weak_err_app_timeout(void) { return (void *)ErrAppTimeOut; }
/* NULL when FatalError is the default above: TROL's own default then runs, as for the others. */
void *trol_weak_fatal_error(void)
{
    return (void *)FatalError == (void *)trol_default_fatal_error ? (void *)0 : (void *)FatalError;
}
