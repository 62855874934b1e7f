//! The commands of docs/extending.md, described once and used by both sides.

use trol::{Arg, ArgKind, Code, CommandDef, Location, Reply, ReplyKind, Robot, Tag, Value, Wait};
use trol_controller::{Backend, Call, Context, Executed, Handler, Pcp, PosMode, RegisterError};
use trol_sim::{SimBackend, SimSettings};

/// Step 1: the descriptions. CAT2 (code 64, the first of its class): the cartesian pose of
/// given joint angles, a float vector, as the manual's CAT2 suggests.
pub const FORWARD_KIN: CommandDef = CommandDef {
    code: 64,
    name: "TROLForwardKin",
    args: &[Arg {
        name: "pJoints",
        kind: ArgKind::Loc {
            tags: &[Tag::Joint],
            min: 1,
            max: 6,
        },
    }],
    reply: ReplyKind::Reals { min: 6, max: 6 },
    success: &[],
    wait: Wait::Reply,
    help: "the cartesian pose (x y z mm, yaw pitch roll rad) of the given joint angles",
};

/// CAT1 (code 18, the next after TROLSpeed): one joint to an absolute angle.
pub const JOINT_ABS: CommandDef = CommandDef {
    code: 18,
    name: "TROLJointAbs",
    args: &[
        Arg {
            name: "jointNum",
            kind: ArgKind::Int { min: 1, max: 6 },
        },
        Arg {
            name: "radians",
            kind: ArgKind::Real,
        },
    ],
    reply: ReplyKind::Code,
    success: &[],
    wait: Wait::Reply,
    help: "move joint jointNum to an absolute angle, the others staying",
};

/// Step 2: the controller's handlers. A CAT1 handler calls the backend and returns the BIOS
/// value; the server builds the reply and keeps GetStatus's record.
pub fn joint_abs<B: Backend>(backend: &mut B, call: &Call<'_>) -> Result<Executed, Code> {
    let (joint, radians) = (call.int(0)? as usize, call.real(1)?);
    let mut q = backend
        .position(Tag::Joint, PosMode::Commanded)?
        .to_array6();
    q[joint - 1] = radians;
    Ok(Executed::Now(backend.ma(q)?))
}

/// A CAT2 handler builds its reply itself, and records its BIOS call for GetStatus.
pub fn forward_kin(ctx: &mut Context<'_, SimBackend>, call: &Call<'_>) -> Reply {
    let q = match call.six(0) {
        Ok(q) => q,
        Err(code) => return Reply::Code(code),
    };
    let pose = ctx.backend.arm().kinematics().fk_xyzypr(&q);
    Reply::Reals {
        value: ctx.status.record_bios(0),
        values: pose.to_vec(),
    }
}

/// Registration (the manual's `dispatchTableX[code - X*64] = handler`): the simulated arm's
/// server with the guide's commands added.
pub fn server(settings: SimSettings) -> Result<Pcp<SimBackend>, RegisterError> {
    let mut pcp = Pcp::new(SimBackend::new(settings));
    pcp.register(JOINT_ABS, Handler::Cat1(joint_abs))?;
    pcp.register(FORWARD_KIN, Handler::Other(forward_kin))?;
    Ok(pcp)
}

/// Step 3: the client's typed calls.
pub fn forward_kin_of(robot: &mut Robot, joints: &[f64]) -> trol::Result<[f64; 6]> {
    let args = [Value::Loc(Location::Joint(joints.to_vec()))];
    match robot.call(&FORWARD_KIN, &args)? {
        Reply::Reals { values, .. } => {
            let mut pose = [0.0; 6];
            pose.copy_from_slice(&values);
            Ok(pose)
        }
        other => unreachable!("the description allows only six reals, got {other:?}"),
    }
}

/// TROLJointAbs from Rust.
pub fn joint_abs_to(robot: &mut Robot, joint: u8, radians: f64) -> trol::Result<()> {
    robot
        .call(&JOINT_ABS, &[Value::Int(joint), Value::Real(radians)])
        .map(drop)
}
