/*
 * extending.c - the guide's commands called from C (docs/extending.md, step 4): a CAT2
 * command through TransSR(), a CAT1 command through Cat1Transaction(). Run it against a
 * controller that serves them (cargo run -p trol --example extending_controller), with
 * trol.cfg's port set to where that controller serves.
 */
#include <stdio.h>
#include <string.h>
#include "trol.h"

#define TROL_JOINT_ABS   18 /* CAT1: jointNum u8, radians f32 at offset 2 */
#define TROL_FORWARD_KIN 64 /* CAT2: dims byte, joint values; reply i16 + 6 floats */

int main(void)
{
    TUCHAR req[2 + 3 * 4];
    TUCHAR joint_abs[6];
    float q[3] = {0.0f, 0.5f, 1.0f};
    float radians = 0.25f;
    float pose[6];
    SInData in;
    SOutData out;
    SLocData pos;
    TINT value;
    TUINT r;

    if (InitTROL(1) != INITTROL_SUCCESS) {
        fprintf(stderr, "extending: InitTROL failed\n");
        return 1;
    }

    /* TROLForwardKin: code, dims byte (numDims 3, POS_JOINT, not straight), 3 floats. */
    req[0] = TROL_FORWARD_KIN;
    req[1] = (3 << 4) | (POS_JOINT << 1);
    memcpy(req + 2, q, sizeof q);
    in.numBytes = sizeof req;
    in.data = req;
    r = TransSR(&in, &out);
    if (r != TRANS_SUCCESS || out.numBytes != 2 + sizeof pose) {
        fprintf(stderr, "extending: TransSR returned %u, %u bytes\n", r, out.numBytes);
        return 1;
    }
    memcpy(&value, out.data, 2);
    memcpy(pose, out.data + 2, sizeof pose);
    printf("TROLForwardKin -> %d: x %.3f y %.3f z %.3f\n", value, pose[0], pose[1], pose[2]);

    /* TROLJointAbs: code, jointNum, radians (word-aligned at offset 2). */
    TROLHome(0);
    joint_abs[0] = TROL_JOINT_ABS;
    joint_abs[1] = 2;
    memcpy(joint_abs + 2, &radians, 4);
    in.numBytes = sizeof joint_abs;
    in.data = joint_abs;
    printf("TROLJointAbs(2, 0.25) -> %d\n", Cat1Transaction(&in));
    TROLFinish(FINISH_WAIT);
    pos.tag = POS_JOINT;
    TROLGetPosition(&pos, POS_COMMANDED);
    printf("joint 2 now %.3f\n", pos.data.joint[1]);

    /* Out of range: the controller refuses it before its handler runs. */
    joint_abs[1] = 7;
    printf("TROLJointAbs(7, 0.25) -> %d\n", Cat1Transaction(&in));
    printf("extending: done\n");
    return 0;
}
