/*
 * A 1998 application's checks (issue 62): the manual's calls only, as a program of the time
 * drives its arm, each call's result checked where a program would check it (its return
 * value, TROLGetStatus, and where TROLGetPosition says the arm stands). Every check prints
 * one line, "check N ok: ..." or "check N FAILED: ...", and the last line says how many
 * passed. Run in a folder whose trol.cfg names the controller; the controller has the
 * examples' locations (test_001). Driven by crates/trol-cli/tests/app_1998.rs on every
 * controller.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include "trol.h"

static int checks, passed;

static void check(int ok, const char *what, TINT got)
{
    checks++;
    if (ok) {
        passed++;
        printf("check %d ok: %s (%d)\n", checks, what, got);
    } else {
        printf("check %d FAILED: %s (%d)\n", checks, what, got);
    }
    fflush(stdout);
}

static void sleep_ms(long ms)
{
    struct timespec t = { ms / 1000, (ms % 1000) * 1000000L };
    nanosleep(&t, NULL);
}

/* Where the arm is: joints (radians) or the tool's pose (mm, radians), actual. */
static TINT where(SLocData *p, TUCCHAR tag)
{
    memset(p, 0, sizeof *p);
    p->tag = tag;
    return TROLGetPosition(p, POS_ACT);
}

static int near_joints(const SLocData *p, const float *q, float tol)
{
    int i;
    for (i = 0; i < 6; i++) {
        if (fabsf(p->data.joint[i] - q[i]) > tol) return 0;
    }
    return 1;
}

static float dist_mm(const SLocData *a, const SLocData *b)
{
    float dx = a->data.cart[0] - b->data.cart[0];
    float dy = a->data.cart[1] - b->data.cart[1];
    float dz = a->data.cart[2] - b->data.cart[2];
    return sqrtf(dx * dx + dy * dy + dz * dz);
}

/* A motion and its TROLFinish(FINISH_WAIT): the first failure's code, or 0. */
static TINT moved(TINT r)
{
    if (r != 0) return r;
    return TROLFinish(FINISH_WAIT);
}

/* Joint by joint (TROLJoint, each waited for) to q: not a check, a way there. */
static TINT go_to(const float *q)
{
    SLocData p;
    int i;
    TINT r = where(&p, POS_JOINT);
    for (i = 0; r == 0 && i < 6; i++) {
        float d = q[i] - p.data.joint[i];
        if (fabsf(d) > 0.001f) r = moved(TROLJoint(i + 1, d));
    }
    return r;
}

/* The work pose: within every A465's reach, the tool ahead and down (TROL's joints). */
static const float WORK[6] = { 0.3f, 0.2f, 0.9f, -0.4f, 0.6f, 0.5f };
static const float JOINT_TOL = 0.005f;
static const float MM_TOL = 1.0f;

int main(void)
{
    SLocData home, p, q, c0, c1, disp;
    float target[6];
    int last = 0;
    TINT r, r2, called;

    check(InitTROL(1) == INITTROL_SUCCESS, "InitTROL(1)", 0);
    r = TROLSpeed(50);
    check(r == 0, "TROLSpeed(50)", r);

    /* Home, and what GetStatus says of it. */
    r = TROLHome(0);
    check(r == 0, "TROLHome(0)", r);
    r = TROLFinish(FINISH_WAIT);
    check(r == 0, "TROLFinish(FINISH_WAIT) after Home", r);
    called = TROLGetStatus(&last);
    check(called == 1 && last == 0, "TROLGetStatus after Home: BIOS called, returned 0", last);
    r = where(&home, POS_JOINT);
    check(r == 0 && home.numDims == 6, "TROLGetPosition(joint, actual): six joints", r);
    memset(&q, 0, sizeof q);
    q.tag = POS_JOINT;
    r = TROLGetPosition(&q, POS_COMMANDED);
    check(r == 0 && near_joints(&q, home.data.joint, JOINT_TOL),
          "commanded and actual position agree at rest", r);

    /* One joint, there and back. */
    r = moved(TROLJoint(1, 0.3f));
    where(&p, POS_JOINT);
    memcpy(target, home.data.joint, sizeof target);
    target[0] += 0.3f;
    check(r == 0 && near_joints(&p, target, JOINT_TOL), "TROLJoint(1, 0.3) arrives", r);
    r = moved(TROLJoint(1, -0.3f));
    where(&p, POS_JOINT);
    check(r == 0 && near_joints(&p, home.data.joint, JOINT_TOL), "TROLJoint(1, -0.3) back", r);

    /* Joint by joint to the work pose. */
    r = go_to(WORK);
    where(&p, POS_JOINT);
    check(r == 0 && near_joints(&p, WORK, JOINT_TOL), "six TROLJoint calls reach the work pose",
          r);

    /* MI and MA: several joints at once. */
    memset(&q, 0, sizeof q);
    q.tag = POS_JOINT;
    q.numDims = 6;
    q.data.joint[0] = 0.05f;
    q.data.joint[1] = -0.05f;
    r = moved(TROLMI(&q));
    where(&p, POS_JOINT);
    memcpy(target, WORK, sizeof target);
    target[0] += 0.05f;
    target[1] -= 0.05f;
    check(r == 0 && near_joints(&p, target, JOINT_TOL), "TROLMI of two joints arrives", r);
    memset(&q, 0, sizeof q);
    q.tag = POS_JOINT;
    q.numDims = 6;
    memcpy(q.data.joint, WORK, sizeof WORK);
    r = moved(TROLMA(&q));
    where(&p, POS_JOINT);
    check(r == 0 && near_joints(&p, WORK, JOINT_TOL), "TROLMA back to the work pose", r);
    go_to(WORK);

    /* Two motions back to back, one Finish. */
    r = TROLJoint(6, 0.2f);
    r2 = TROLJoint(6, -0.2f);
    check(r == 0 && r2 == 0, "two TROLJoint calls back to back are taken", r2);
    r = TROLFinish(FINISH_WAIT);
    where(&p, POS_JOINT);
    check(r == 0 && near_joints(&p, WORK, JOINT_TOL), "... and both ran: the arm is back", r);
    go_to(WORK);

    /* Out of range: refused, nothing moves. */
    r = TROLJoint(1, 4.0f);
    called = TROLGetStatus(&last);
    TROLFinish(FINISH_WAIT);
    where(&p, POS_JOINT);
    check(r != 0, "TROLJoint(1, 4.0) beyond the joint's range is refused", r);
    check(near_joints(&p, WORK, JOINT_TOL), "... and nothing moved", r);
    check(last == r, "TROLGetStatus right after it names the refusal", last);

    /* Cartesian: the pose, a line down and back, Depart. */
    r = where(&c0, POS_CART);
    check(r == 0 && c0.numDims == 6, "TROLGetPosition(cart, actual): six values", r);
    q = c0;
    q.data.cart[2] -= 20.0f;
    r = moved(TROLMoveII(&q, 0));
    where(&c1, POS_CART);
    check(r == 0 && dist_mm(&c1, &q) <= MM_TOL, "TROLMoveII 20 mm down arrives", r);
    r = moved(TROLMoveII(&c0, 1));
    where(&c1, POS_CART);
    check(r == 0 && dist_mm(&c1, &c0) <= MM_TOL, "TROLMoveII straight back up arrives", r);
    memset(&disp, 0, sizeof disp);
    disp.tag = POS_CART;
    disp.numDims = 1;
    disp.data.cart[0] = -30.0f;
    r = moved(TROLDepart(&disp, 1));
    where(&c1, POS_CART);
    check(r == 0 && fabsf(dist_mm(&c1, &c0) - 30.0f) <= MM_TOL, "TROLDepart 30 mm", r);
    r = moved(TROLMoveII(&c0, 0));
    where(&c1, POS_CART);
    check(r == 0 && dist_mm(&c1, &c0) <= MM_TOL, "TROLMoveII back", r);

    /* The manual's pick: Appro, Move, Close, Depart (the Depart without a Finish after the
     * Close, as many programs did). */
    r = moved(TROLOpen(50));
    check(r == 0, "TROLOpen(50) and Finish", r);
    disp.data.cart[0] = -90.0f;
    r = moved(TROLAppro("test_001", &disp, 0));
    check(r == 0, "TROLAppro(test_001, -90 mm) arrives", r);
    r = moved(TROLMove("test_001", 1));
    where(&c1, POS_CART);
    q.data.cart[0] = 400.0f;
    q.data.cart[1] = 0.0f;
    q.data.cart[2] = 150.0f;
    check(r == 0 && dist_mm(&c1, &q) <= MM_TOL, "TROLMove(test_001, straight) arrives there",
          r);
    r = TROLClose(60);
    check(r == 0, "TROLClose(60)", r);
    r = TROLDepart(&disp, 1);
    check(r == 0, "TROLDepart right after TROLClose is taken", r);
    r = TROLFinish(FINISH_WAIT);
    where(&c1, POS_CART);
    check(r == 0 && fabsf(dist_mm(&c1, &q) - 90.0f) <= MM_TOL,
          "... and ran after the fingers closed: 90 mm away", r);
    r = moved(TROLGrip(30));
    check(r == 0, "TROLGrip(30) and Finish", r);
    r = moved(TROLOpen(50));
    check(r == 0, "TROLOpen(50) again", r);

    /* A name the controller does not know. */
    r = TROLMove("nowhere", 0);
    called = TROLGetStatus(&last);
    check(r == TROL_ERR_LOCATION, "TROLMove(nowhere) is TROL_ERR_LOCATION", r);
    check(called == 0 && last == TROL_ERR_LOCATION, "... the BIOS not called", called);

    /* Halt during a slow motion: it stops short, and the next motion works. */
    r = go_to(WORK);
    check(r == 0, "back to the work pose", r);
    TROLSpeed(5);
    r = TROLJoint(1, 1.2f);
    check(r == 0, "a slow TROLJoint(1, 1.2)", r);
    sleep_ms(50);
    r = TROLHalt();
    check(r == 0, "TROLHalt()", r);
    TROLFinish(FINISH_WAIT);
    where(&p, POS_JOINT);
    check(p.data.joint[0] < WORK[0] + 1.2f - 0.05f, "... the arm stopped short of the target",
          0);
    TROLSpeed(50);
    r = go_to(WORK);
    check(r == 0, "the motion after the Halt arrives", r);

    /* The tool transform: the tool's point 100 mm out along the flange's axis. */
    where(&c0, POS_CART);
    memset(&q, 0, sizeof q);
    q.tag = POS_CART;
    q.numDims = 6;
    q.data.cart[2] = 100.0f;
    r = TROLSetToolTransform(&q);
    where(&c1, POS_CART);
    check(r == 0 && fabsf(dist_mm(&c1, &c0) - 100.0f) <= MM_TOL,
          "TROLSetToolTransform 100 mm: the tool point 100 mm from the flange", r);
    q.data.cart[2] = 0.0f;
    r = TROLSetToolTransform(&q);
    where(&c1, POS_CART);
    check(r == 0 && dist_mm(&c1, &c0) <= MM_TOL, "TROLSetToolTransform back to none", r);

    /* Jog: 10 mm up in a straight line. */
    memset(&disp, 0, sizeof disp);
    disp.tag = POS_CART;
    disp.numDims = 3;
    disp.data.cart[2] = 10.0f;
    r = moved(TROLJog(&disp, 1));
    where(&c1, POS_CART);
    check(r == 0 && fabsf(c1.data.cart[2] - c0.data.cart[2] - 10.0f) <= MM_TOL &&
              fabsf(c1.data.cart[0] - c0.data.cart[0]) <= MM_TOL,
          "TROLJog 10 mm up", r);

    /* Idle: FINISH_STATUS says nothing moves. */
    r = TROLFinish(FINISH_STATUS);
    check(r == 0, "TROLFinish(FINISH_STATUS) with the arm at rest", r);

    /* Ready, then Home again: the same home pose. */
    r = moved(TROLReady());
    check(r == 0, "TROLReady and Finish", r);
    r = moved(TROLHome(0));
    where(&p, POS_JOINT);
    check(r == 0 && near_joints(&p, home.data.joint, JOINT_TOL),
          "TROLHome(0) again ends at the same home pose", r);

    r = (TINT)CleanupTROL();
    check(r == 0, "CleanupTROL()", r);
    printf("checks: %d passed of %d\n", passed, checks);
    return passed == checks ? 0 : 1;
}
