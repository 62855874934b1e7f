/*
 * trol.h - the TROL API (TU Vienna Robot Control Library) for the CRS A465 / C500.
 *
 * Names, types and codes as in the manual (Melzer, TROL 2.1, 1998): chapter "TROL API",
 * "Rückgabewerte und Fehlercodes", "Callback-Routinen". Build against libtrol:
 *
 *     cc app.c -Iinclude -Ltarget/release -ltrol -lpthread -ldl -lm
 *
 * Every function returns the manual's codes: 0 = success, > -32000 a BIOS code,
 * <= -32000 a TROL code. Values the manual names without giving them (FINISH_*, POS_COMMANDED,
 * POS_ACT, RECOVERY_*, INITTROL_*) are fixed in docs/protocol.md.
 */
#ifndef TROL_H
#define TROL_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* troltype.h: the manual's sizes on every platform. */
typedef int32_t  TLONG;
typedef uint32_t TULONG;
typedef int16_t  TINT;
typedef uint16_t TUINT;
typedef uint16_t TBOOL;
typedef int8_t   TCHAR;
typedef uint8_t  TUCHAR;
typedef uint8_t  TUCCHAR;

#define POS_PREC  0  /* precision point (motor) location */
#define POS_JOINT 1  /* joint (angular) location */
#define POS_CART  2  /* cartesian location */

#define POS_COMMANDED 0
#define POS_ACT       1

#define FINISH_STATUS 0
#define FINISH_WAIT   1

#define RECOVERY_SUCCESS 0
#define RECOVERY_FAIL    1

#define INITTROL_SUCCESS 0
#define INITTROL_FAILURE 1

/* Layer-4 codes. */
#define TROL_ERR_COMM      (-32001)
#define TROL_ERR_BAD_RSIZE (-32002)
#define TROL_ERR_ARG_RANGE (-32003)
#define TROL_ERR_NOT_INIT  (-32004) /* called before InitTROL succeeded, or after CleanupTROL: nothing was sent (not in the manual) */
#define TROL_ERR_UNKNOWN   (-32051)
#define TROL_ERR_BAD_CSIZE (-32052)
#define TROL_ERR_ROBOT     (-32053) /* the command did not reach the robot (link failed, answer unreadable); it did not run (not in the manual) */
#define TROL_ERR_ROBOT_UNSURE (-32054) /* the link to the robot failed after the command was sent: it may have run (not in the manual) */
#define TROL_ERR_NOT_STOPPED (-32055) /* Halt: every stop was sent and the arm was not seen standing: it may still move (not in the manual) */
#define TROL_ERR_HALTED    (-32056) /* Finish: the motion was halted by someone else (pendant, another program, watchdog) (not in the manual) */
#define TROL_RETVAL_RANGE  (-32101)
#define TROL_ERR_LOCATION  (-32102)

/* Layer-3 codes (TransSR / TransRS). */
#define TRANS_SUCCESS     0x00
#define TRANS_ERR_SEND    0x01
#define TRANS_ERR_RECEIVE 0x02
#define TRANS_TIMEOUT     0x03

/* Layer-2 codes: NAK codes, SendData and ReceiveData return values (GetLastCommErr;
 * mask with 0xff, the high byte holds the NAK code for ERR_NAK and ERR_ABORT). */
#define ERR_FID       0x01
#define ERR_ETB       0x02
#define ERR_TOO_LARGE 0x04
#define ERR_BCC       0xf1
#define ERR_STX       0xf2
#define ERR_ETX       0xf4
#define ERR_SOH       0xf8
#define ERR_WRONG_CCHAR    0x01
#define ERR_NAK            0x02
#define ERR_TIMEOUT_ENQ    0x03
#define ERR_TIMEOUT_NAK    0x04
#define ERR_TIMEOUT_ETX    0x05
#define ERR_LIMIT_EXCEEDED 0x07
#define ERR_ABORT          0x80
#define ERR_TIMEOUT_SOH    0x81
#define ERR_TIMEOUT_STX    0x82
#define ERR_TIMEOUT_TERMC  0x83
#define ERR_TIMEOUT_EOT    0x84
#define ERR_BAD_ENQ        0x85
#define ERR_BAD_EOT        0x86

/* Command codes (commands.h). */
#define TROL_APPRO 0
#define TROL_APPRO_II 1
#define TROL_CLOSE 2
#define TROL_DEPART 3
#define TROL_FINISH 4
#define TROL_GRIP 5
#define TROL_HALT 6
#define TROL_HOME 7
#define TROL_JOG 8
#define TROL_JOINT 9
#define TROL_MA 10
#define TROL_MI 11
#define TROL_MOVE 12
#define TROL_MOVE_II 13
#define TROL_OPEN 14
#define TROL_READY 15
#define TROL_SET_TOOL_TRANSFORM 16
#define TROL_SPEED 17
#define LAST_CAT1_CODE 17
#define LAST_CAT2_CODE 63
#define TROL_GET_POSITION 128
#define TROL_GET_GRIPPER 129
#define TROL_LIST_LOCATIONS 130
#define TROL_HERE 131
#define TROL_DEFINE 132
#define TROL_DELETE_LOCATION 133
#define TROL_SAVE_LOCATIONS 134
#define TROL_TRAJECTORY 135
#define LAST_CAT3_CODE 135
#define TROL_TERMINATE_PCP 192
#define TROL_GET_STATUS 193
#define TROL_GET_VERSION 194
#define TROL_SET_WATCHDOG 195
#define TROL_GET_CODES 196
#define TROL_GET_REPLY_TIME 197
#define LAST_CAT4_CODE 197

/* The manual requires structure alignment off or 16 bit. */
#pragma pack(push, 2)
typedef struct
{
    TUCCHAR tag;      /* POS_PREC, POS_JOINT or POS_CART */
    TUCCHAR numDims;  /* number of relevant coordinates */
    union
    {
        TLONG prec[8];   /* motor location */
        float joint[8];  /* joint location */
        float cart[8];   /* cartesian location */
    } data;
}
SLocData;
#pragma pack(pop)

/* 8 bytes, blank-padded, not NUL-terminated (a shorter NUL-terminated string is accepted). */
typedef TUCCHAR TLocName[8];

/* A message handed to an error handler. */
typedef struct { TUINT numBytes; TUCHAR *data; } SInData;
typedef SInData SOutData;

/* CAT1 */
TINT TROLAppro(TLocName locName, SLocData *pDisp, TUINT straight);
TINT TROLApproII(SLocData *pTarget, SLocData *pDisp, TUINT straight);
TINT TROLClose(TUINT perForce);
TINT TROLDepart(SLocData *pDisp, TUINT straight);
TINT TROLFinish(TUINT mode);
TINT TROLGrip(TUINT dist);
TINT TROLHalt(void);
TINT TROLHome(TUINT axis);
TINT TROLJog(SLocData *pDisp, TUINT straight);
TINT TROLJoint(TUINT jointNum, float radians);
TINT TROLMA(SLocData *pTarget);
TINT TROLMI(SLocData *pDisp);
TINT TROLMove(TLocName locName, TUINT straight);
TINT TROLMoveII(SLocData *pTarget, TUINT straight);
TINT TROLOpen(TUINT perForce);
TINT TROLReady(void);
TINT TROLSetToolTransform(SLocData *md);
TINT TROLSpeed(TUINT perMaxSpeed);
/* CAT3 */
/* TROLGetPosition: set pos->tag first: it chooses the form read (POS_CART: x y z mm, yaw
 * pitch roll rad; POS_JOINT: rad; POS_PREC: encoder counts); mode is POS_COMMANDED or
 * POS_ACT. The six values and numDims come back in *pos. */
TINT TROLGetPosition(SLocData *pos, TINT mode);
/* CAT4 */
TINT TROLTerminatePCP(void);
TINT TROLGetStatus(int *lastBIOSRetVal);
/* Additions for the manual's GetStatus method: which transaction the status belongs to and
 * the controller's epoch (it changes when the controller restarts); and the number of the
 * last request sent. After a CAT1/CAT2 call whose outcome never came back (TROL_ERR_COMM, or
 * TROL_ERR_ROBOT_UNSURE from a repeat the controller could not place), GetStatus and
 * GetStatusOf speak of that call, never of an older one (docs/reliability.md, "Exactly
 * once"):
 *   n = TROLLastTransaction();                     at once after the failed call: every
 *                                                  request, GetStatus too, takes a number
 *   called = TROLGetStatusOf(&last, &t, &e);      t == n: the failed call's status
 *   called == 0                    it never ran: send it again
 *   called == 1, last == TROL_ERR_ROBOT_UNSURE    it may have run (the controller restarted
 *                                  and its journal, if any, could not place it): do NOT send
 *                                  it again blindly; read the arm (TROLGetPosition) and
 *                                  compare with where it was before the call
 *   called == 1, otherwise         it ran, with result last: do not send it again
 * The manual's TROLGetStatus gives the same called and last. e differs from the epoch of an
 * earlier GetStatus when the controller restarted. A controller that speaks only the manual's
 * protocol answers GetStatus in the manual's 4 bytes: t and e are then 0 (no request is
 * numbered 0, no controller draws epoch 0), and its status is its own last call's. */
TINT TROLGetStatusOf(int *lastBIOSRetVal, TUINT *transaction, TUINT *epoch);
TUINT TROLLastTransaction(void);
/* Added (docs/protocol.md "Version and kind", "Watchdog"). TROLGetVersion: the protocol
 * version the controller speaks (TROL_PROTOCOL_VERSION on both ends) and, in kind (kindSize
 * bytes, NUL-terminated, cut if longer), what drives its arm; InitTROL checks it.
 * TROLSetWatchdog: the controller halts the arm when no call arrives for tenths/10 s
 * (1..250; 0 turns it off). */
#define TROL_PROTOCOL_VERSION 4
TINT TROLGetVersion(TUINT *protocol, char *kind, TUINT kindSize);
TINT TROLSetWatchdog(TUINT tenths);
/* Added (docs/protocol.md "Codes"). TROLGetCodes: the controller's BIOS codes: up to max of
 * their values into values, how many there are into *count; InitTROL and trol_connect read
 * them, and trol_strerror names each as that controller does. */
TINT TROLGetCodes(TINT *values, TUINT max, TUINT *count);
/* Added (docs/protocol.md "Reply time"). TROLGetReplyTime: the longest the controller takes
 * to answer a request, in seconds; InitTROL and trol_connect read it, and each call then
 * waits that and a margin for its reply (a dead controller is noticed within seconds),
 * unless SetL3_TO_Intervall set the reply timeout. */
TINT TROLGetReplyTime(float *seconds);
/* Added (docs/protocol.md "Gripper"). TROLGetGripper: the fingers' opening (mm) and what they
 * hold, to check a grasp: GRIPPER_EMPTY (closed on air, or open), GRIPPER_HOLDS (the object's
 * name in name, nameSize bytes, NUL-terminated; empty when the controller knows none), or
 * GRIPPER_UNKNOWN (the controller reads the opening only). A controller that cannot read its
 * gripper answers TROL_ERR_UNKNOWN. */
#define GRIPPER_EMPTY 0
#define GRIPPER_HOLDS 1
#define GRIPPER_UNKNOWN 2
TINT TROLGetGripper(float *openingMm, TINT *held, char *name, TUINT nameSize);
/* Added (docs/teach.md): teaching. TROLHere stores where the arm is (commanded) under locName
 * in the form pos (POS_CART, POS_JOINT, or POS_PREC for a name starting with '#');
 * TROLDefine stores *pLoc (six values) under locName; TROLDeleteLocation forgets locName
 * (TROL_ERR_LOCATION if there is none); TROLSaveLocations keeps the table across a restart
 * (the simulator writes its locations file); TROLListLocations gives up to max of the
 * locations, sorted by name (names NUL-padded to 8 bytes), and how many there are in *count
 * (names and locs may be NULL with max 0). A name of the wrong form for its location, or a
 * NULL pointer, is TROL_ERR_ARG_RANGE, and nothing is sent. */
TINT TROLHere(TLocName locName, TINT pos);
TINT TROLDefine(TLocName locName, SLocData *pLoc);
TINT TROLDeleteLocation(TLocName locName);
TINT TROLSaveLocations(void);
TINT TROLListLocations(TLocName *names, SLocData *locs, TUINT max, TUINT *count);
/* Added (docs/protocol.md "Trajectory"): one motion through count waypoints, each a time in
 * seconds from the start (0 or more, increasing) and six joint angles in radians, as a
 * planner's trajectory is run: the simulated A465 and a MARS 8 keep the times (refused with
 * BIOS_TOO_FAST, before anything moves, where they ask more than the arm's limits at the
 * speed setting); a controller that cannot returns TRAJECTORY_UNTIMED (1): one joint move to
 * each waypoint, at the speed setting. Wait with TROLFinish(FINISH_WAIT). At most
 * MAX_WAYPOINTS points; a NULL points, no points or times that do not increase are
 * TROL_ERR_ARG_RANGE, and nothing is sent. */
typedef struct { float time; float joints[6]; } STrajPoint;
#define MAX_WAYPOINTS 500
#define TRAJECTORY_UNTIMED 1
TINT TROLTrajectory(const STrajPoint *points, TUINT count);

/* Other functions */
TUINT InitTROL(TUINT serOnly);
TUINT CleanupTROL(void);
void SetL3_TO_Intervall(TUINT TO_Intervall);
void SetDelay(TUINT delay);           /* milliseconds between two bytes sent */
/* How often a request whose reply was lost is sent again, marked REPEAT, so that it runs
 * exactly once; 0..10 (an addition: 0 is the manual's behaviour). Without this call: 2 once
 * InitTROL found a controller of this protocol (it remembers its last request), 0 for one
 * that speaks only the manual's (a 1998 TROL server). An error handler that returns
 * RECOVERY_FAIL ends the call without a repeat. */
void TROLSetRepeats(TUINT repeats);
TUINT GetLastCommErr(void);           /* the last call's layer-2 failure, 0 if none */
/* Added: which service that failure belongs to (ERR_LIMIT_EXCEEDED is 0x07 on both sides),
 * and the code of a port that failed outright (an I/O error: the process behind a pty or a
 * TCP connection is gone), on the send side and the receive side. */
#define COMM_SIDE_SEND 1
#define COMM_SIDE_RECEIVE 2
#define ERR_PORT_SEND 0x08
#define ERR_PORT_RECEIVE 0x88
TUINT GetLastCommSide(void);

/* Adding commands ("Erweiterung von TROL um eigene Kommandos", docs/extending.md).
 * Cat1Transaction (send.h): send a CAT1 request (its first byte the command code) and
 *   return the reply's value as the API functions do (failures through FatalError).
 * TransSR (layer 3): send any request and receive its reply; resp->data stays valid until
 *   the next TransSR on this thread. Returns TRANS_SUCCESS or a TRANS_* code. */
TINT Cat1Transaction(SInData *req);
TUINT TransSR(SInData *req, SOutData *resp);

/* Layers 2 and 1, for error handlers that mend a failure themselves ("Callback-Routinen"):
 * inside a handler they work on the line of the failed transaction, elsewhere on the
 * connection's. ReceiveData's out->data stays valid until the next ReceiveData on this
 * thread. SendData and ReceiveData return 0 or the layer-2 code (0x00FF: the port failed;
 * 0x0081 ERR_TIMEOUT_SOH from ReceiveData: no message started within the reply timeout;
 * 0x00FF at once, and nothing received, when out or PCI is NULL). */
TUINT SendData(SInData *in, TUINT PCI);
TUINT ReceiveData(SOutData *out, TUINT *PCI);
TBOOL BufferEmpty(void);              /* 1: no byte waits in the input */
void FlushBuffer(void);

/* Error handlers (callback.c), the manual's way: define any of these four in your program
 * and TROL calls it (with libtrol.so and libtrol.a alike); leave it out and TROL's default
 * runs. ErrOnReceive that returns RECOVERY_SUCCESS must point *out at the message it
 * received (with ReceiveData) and set *PCI; ErrAppTimeOut may look with BufferEmpty() but
 * must not take a byte. FatalError is also defined in libtrol (returning errorCode), so that
 * an added API function may call it, as the manual's own do, in a program without one. */
TUINT ErrOnSend(SInData *in, TUINT *PCI);
TUINT ErrOnReceive(SOutData *out, TUINT *PCI);
TUINT ErrAppTimeOut(SInData *in);
TINT FatalError(TUINT command, TINT errorCode);

/* Or install handlers at run time (these take precedence); NULL restores the above. */
typedef TUINT (*TROLErrOnSendFn)(SInData *in, TUINT *PCI);
typedef TUINT (*TROLErrOnReceiveFn)(SOutData *out, TUINT *PCI);
typedef TUINT (*TROLErrAppTimeOutFn)(SInData *in);
typedef TINT (*TROLFatalErrorFn)(TUINT command, TINT errorCode);
void TROLSetErrOnSend(TROLErrOnSendFn handler);
void TROLSetErrOnReceive(TROLErrOnReceiveFn handler);
void TROLSetErrAppTimeOut(TROLErrAppTimeOutFn handler);
void TROLSetFatalError(TROLFatalErrorFn handler);

/* Connections, libmodbus-style (an addition): any number of arms in one process, each
 * connection with its own settings and error handlers, each usable from its own thread.
 * trol_connect: the port as trol.cfg's second line names it (a serial device,
 * socket://HOST:PORT, "sim", "rapl:DEVICE"), checked as InitTROL(1) checks; NULL on failure,
 * with the reason from trol_connect_error() (this thread's last). trol_disconnect closes and
 * frees it (the controller stays in server mode; trol_terminate_pcp ends that).
 * trol_strerror: a return code as "NAME: meaning", a static string (BIOS codes as the default
 * connection's controller names them, TROLGetCodes; in an error handler, its connection's);
 * trol_strerror_for: as connection c's controller names them. GetLastCommErr and
 * GetLastCommSide are per connection (trol_get_last_comm_err, trol_get_last_comm_side; the
 * manual's names read the default connection's, or in an error handler its own): no
 * connection's call resets another's. Every manual function
 * TROLName(args) has trol_name(TROL *, args) (NULL: TROL_ERR_ARG_RANGE, nothing sent). The
 * manual's functions above drive one default connection, as before. An error handler that
 * calls TROL on its own connection gets TROL_ERR_COMM at once; other connections work. */
typedef struct TROL TROL;
TROL *trol_connect(const char *port, TLONG baud);
const char *trol_connect_error(void);
/* What kind of failure the last trol_connect on this thread met (the Rust API's SetupError,
 * typed for C); after TROL_SETUP_INCOMPATIBLE, trol_connect_versions gives this library's
 * protocol version and the controller's (0: it does not know TROLGetVersion). */
#define TROL_SETUP_NONE 0
#define TROL_SETUP_PORT 1         /* the port could not be opened */
#define TROL_SETUP_CONFIG 2       /* the port's name, an argument or a setting is wrong */
#define TROL_SETUP_NO_SERVER 3    /* the controller's TROL server does not answer */
#define TROL_SETUP_INCOMPATIBLE 4 /* it speaks another protocol version */
#define TROL_SETUP_OTHER 5
int trol_connect_error_kind(void);
void trol_connect_versions(TUINT *ours, TUINT *theirs);
void trol_disconnect(TROL *c);
const char *trol_strerror(int code);
const char *trol_strerror_for(const TROL *c, int code);
/* trol_last_error_text: why connection c's last failed call failed, in words (NULL c: the
 * default connection, the manual's functions'): the code's name and meaning, and what an
 * in-process controller's backend said (which profile key a BIOS_UNSETTLED needs, what the
 * controller printed). "" before any failure; valid until c's next failed call. Set
 * TROL_VERBOSE=1 to have the backend's lines printed on stderr as they come. */
const char *trol_last_error_text(const TROL *c);
/* In an error handler shared by several connections: trol_current() is the connection whose
 * call failed (NULL: the default one), and trol_get_user(c) the pointer the application kept
 * with it by trol_set_user(c, user) (NULL c: the default connection's). */
TROL *trol_current(void);
void trol_set_user(TROL *c, void *user);
void *trol_get_user(const TROL *c);
TUINT trol_get_last_comm_err(TROL *c);
TUINT trol_get_last_comm_side(TROL *c);
TINT trol_appro(TROL *c, TLocName locName, SLocData *pDisp, TUINT straight);
TINT trol_appro_ii(TROL *c, SLocData *pTarget, SLocData *pDisp, TUINT straight);
TINT trol_close(TROL *c, TUINT perForce);
TINT trol_depart(TROL *c, SLocData *pDisp, TUINT straight);
TINT trol_finish(TROL *c, TUINT mode);
TINT trol_grip(TROL *c, TUINT dist);
TINT trol_halt(TROL *c);
TINT trol_home(TROL *c, TUINT axis);
TINT trol_jog(TROL *c, SLocData *pDisp, TUINT straight);
TINT trol_joint(TROL *c, TUINT jointNum, float radians);
TINT trol_ma(TROL *c, SLocData *pTarget);
TINT trol_mi(TROL *c, SLocData *pDisp);
TINT trol_move(TROL *c, TLocName locName, TUINT straight);
TINT trol_move_ii(TROL *c, SLocData *pTarget, TUINT straight);
TINT trol_open(TROL *c, TUINT perForce);
TINT trol_ready(TROL *c);
TINT trol_set_tool_transform(TROL *c, SLocData *md);
TINT trol_speed(TROL *c, TUINT perMaxSpeed);
TINT trol_get_position(TROL *c, SLocData *pos, TINT mode);
TINT trol_terminate_pcp(TROL *c);
TINT trol_get_status(TROL *c, int *lastBIOSRetVal);
TINT trol_get_status_of(TROL *c, int *lastBIOSRetVal, TUINT *transaction, TUINT *epoch);
TUINT trol_last_transaction(TROL *c);
TINT trol_get_version(TROL *c, TUINT *protocol, char *kind, TUINT kindSize);
TINT trol_get_codes(TROL *c, TINT *values, TUINT max, TUINT *count);
TINT trol_get_reply_time(TROL *c, float *seconds);
TINT trol_get_gripper(TROL *c, float *openingMm, TINT *held, char *name, TUINT nameSize);
TINT trol_here(TROL *c, TLocName locName, TINT pos);
TINT trol_define(TROL *c, TLocName locName, SLocData *pLoc);
TINT trol_delete_location(TROL *c, TLocName locName);
TINT trol_save_locations(TROL *c);
TINT trol_trajectory(TROL *c, const STrajPoint *points, TUINT count);
TINT trol_list_locations(TROL *c, TLocName *names, SLocData *locs, TUINT max, TUINT *count);
TINT trol_set_watchdog(TROL *c, TUINT tenths);
void trol_set_reply_timeout(TROL *c, TUINT tenths);   /* SetL3_TO_Intervall */
void trol_set_repeats(TROL *c, TUINT repeats);
void trol_set_delay(TROL *c, TUINT delay);            /* SetDelay */
TUINT trol_trans_sr(TROL *c, SInData *req, SOutData *resp);
TINT trol_cat1_transaction(TROL *c, SInData *req);
void trol_set_err_on_send(TROL *c, TROLErrOnSendFn handler);
void trol_set_err_on_receive(TROL *c, TROLErrOnReceiveFn handler);
void trol_set_err_app_timeout(TROL *c, TROLErrAppTimeOutFn handler);
void trol_set_fatal_error(TROL *c, TROLFatalErrorFn handler);

#ifdef __cplusplus
}
#endif

#endif /* TROL_H */
