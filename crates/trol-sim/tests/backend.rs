//! The backend contract seen from the server: what a request carries reaches the backend as
//! decoded, bit for bit; a stored location keeps its f64 inside the controller; long calls
//! reply once the backend is idle; a backend's failure is TROL_ERR_LOCATION or
//! TROL_ERR_ROBOT with GetStatus telling the truth.

use trol_a465::arm::Stored;
use trol_controller::{Backend, BackendError, BiosResult, Handled, Pcp, PosMode, Target};
use trol_proto::application::code::{Code, TROL_ERR_LOCATION, TROL_ERR_ROBOT};
use trol_proto::application::record::{self, Value};
use trol_proto::application::table::{self, FINISH_WAIT};
use trol_proto::application::{CodeTable, LocName, Location, Reply, Tag};
use trol_sim::{SimBackend, SimSettings};

/// The simulated arm, with every target it is handed recorded, and a switch that breaks its
/// link.
struct Recorder {
    sim: SimBackend,
    targets: Vec<Target>,
    broken: bool,
    /// The arm keeps moving until a Halt (a long motion, whatever the simulation's speed).
    hold: bool,
}

impl Recorder {
    fn link(&self) -> Result<(), BackendError> {
        if self.broken {
            Err(BackendError::Link("cable pulled".into()))
        } else {
            Ok(())
        }
    }
}

impl Backend for Recorder {
    fn kind(&self) -> &'static str {
        "recorder"
    }
    fn codes(&self) -> &'static CodeTable {
        self.sim.codes()
    }
    fn appro(&mut self, target: &Target, disp: [f64; 6], straight: bool) -> BiosResult {
        self.targets.push(target.clone());
        self.sim.appro(target, disp, straight)
    }
    fn close(&mut self, force: u8) -> BiosResult {
        self.sim.close(force)
    }
    fn depart(&mut self, disp: [f64; 6], straight: bool) -> BiosResult {
        self.sim.depart(disp, straight)
    }
    fn moving(&mut self) -> Result<bool, BackendError> {
        self.link()?;
        Ok(self.hold || self.sim.moving()?)
    }
    fn grip(&mut self, dist: u8) -> BiosResult {
        self.sim.grip(dist)
    }
    fn halt(&mut self) -> BiosResult {
        self.hold = false;
        self.sim.halt()
    }
    fn home(&mut self, axis: u8) -> BiosResult {
        self.sim.home(axis)
    }
    fn jog(&mut self, d: [f64; 3], straight: bool) -> BiosResult {
        self.sim.jog(d, straight)
    }
    fn joint(&mut self, joint: u8, radians: f64) -> BiosResult {
        self.link()?;
        self.sim.joint(joint, radians)
    }
    fn ma(&mut self, q: [f64; 6]) -> BiosResult {
        self.sim.ma(q)
    }
    fn mi(&mut self, dq: [f64; 6]) -> BiosResult {
        self.sim.mi(dq)
    }
    fn move_to(&mut self, target: &Target, straight: bool) -> BiosResult {
        self.targets.push(target.clone());
        self.sim.move_to(target, straight)
    }
    fn open(&mut self, force: u8) -> BiosResult {
        self.sim.open(force)
    }
    fn ready(&mut self) -> BiosResult {
        self.sim.ready()
    }
    fn set_tool(&mut self, tool: [f64; 6]) -> BiosResult {
        self.sim.set_tool(tool)
    }
    fn speed(&mut self, percent: u8) -> BiosResult {
        self.sim.speed(percent)
    }
    fn position(&mut self, tag: Tag, mode: PosMode) -> Result<Location, BackendError> {
        self.sim.position(tag, mode)
    }
}

const X: f64 = 400.123_456_789;

fn server() -> Pcp<Recorder> {
    let settings = SimSettings {
        time_scale: 1000.0,
        locations: vec![("p1".into(), Stored::Cart([X, 0.0, 300.0, 0.0, 1.5, 0.0]))],
        arm: trol_a465::arm::ArmSettings {
            homed: true,
            ..Default::default()
        },
        ..SimSettings::default()
    };
    Pcp::new(Recorder {
        sim: SimBackend::new(settings),
        targets: Vec::new(),
        broken: false,
        hold: false,
    })
}

fn reply(
    pcp: &mut Pcp<Recorder>,
    def: &trol_proto::application::CommandDef,
    args: &[Value],
) -> Reply {
    let request = record::encode(def, args).unwrap();
    let bytes = match pcp.handle(&request) {
        Handled::Reply(bytes) => bytes,
        Handled::Pending => loop {
            if let Some(b) = pcp.poll() {
                break b;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        },
    };
    Reply::decode(def, &bytes).unwrap()
}

fn finish(pcp: &mut Pcp<Recorder>) {
    let request = record::encode(&table::FINISH, &[Value::Int(FINISH_WAIT)]).unwrap();
    if pcp.handle(&request) == Handled::Pending {
        let bytes = loop {
            if let Some(b) = pcp.poll() {
                break b;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        };
        assert_eq!(bytes, [0, 0]);
    }
}

#[test]
fn a_movei_target_reaches_the_backend_bit_for_bit_as_decoded() {
    let mut pcp = server();
    let target = Location::Cart(vec![X, 10.1, 300.3, 0.01, 1.5, 0.02]);
    let request =
        record::encode(&table::MOVE_II, &[Value::Loc(target), Value::Flag(false)]).unwrap();
    let decoded = record::decode(&table::MOVE_II, &request).unwrap();
    let Value::Loc(decoded) = &decoded[0] else {
        panic!()
    };
    assert!(matches!(pcp.handle(&request), Handled::Reply(r) if r == [0, 0]));
    let Target::Location(seen) = &pcp.backend().targets[0] else {
        panic!("{:?}", pcp.backend().targets)
    };
    let bits = |l: &Location| l.values().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(seen), bits(decoded));
    // The wire's f32, widened exactly: nothing narrowed it again on the way.
    assert_eq!(seen.values()[0], f64::from(X as f32));
}

#[test]
fn a_stored_location_reaches_the_arm_in_full_f64() {
    let mut pcp = server();
    let name = LocName::new("p1").unwrap();
    let r = reply(
        &mut pcp,
        &table::MOVE,
        &[Value::Name(name), Value::Flag(false)],
    );
    assert_eq!(r, Reply::Code(Code(0)));
    // The name went through to the backend, which keeps its own table.
    assert_eq!(pcp.backend().targets, [Target::Name(name)]);
    finish(&mut pcp);
    let now = pcp.backend().sim.now();
    let arm = pcp.backend_mut().sim.arm_mut();
    let q = arm.position(now, trol_a465::arm::Which::Commanded);
    let x = arm.kinematics().fk_xyzypr(&q)[0];
    // f32 would have made it 400.12344: an error of 1.3e-5 mm.
    assert!((x - X).abs() < 1e-9, "{x}");
}

#[test]
fn backend_failures_are_refusals_and_getstatus_says_the_bios_was_not_called() {
    let mut pcp = server();
    let nowhere = LocName::new("nowhere").unwrap();
    pcp.set_transaction(11);
    let r = reply(
        &mut pcp,
        &table::MOVE,
        &[Value::Name(nowhere), Value::Flag(false)],
    );
    assert_eq!(r, Reply::Code(TROL_ERR_LOCATION));
    let epoch = pcp.epoch();
    assert_ne!(epoch, 0);
    pcp.set_transaction(12);
    assert_eq!(
        reply(&mut pcp, &table::GET_STATUS, &[]),
        Reply::Status {
            bios_called: false,
            last: TROL_ERR_LOCATION,
            transaction: 11,
            epoch,
        }
    );
    pcp.backend_mut().broken = true;
    pcp.set_transaction(13);
    let r = reply(&mut pcp, &table::JOINT, &[Value::Int(1), Value::Real(0.1)]);
    assert_eq!(r, Reply::Code(TROL_ERR_ROBOT));
    pcp.set_transaction(14);
    assert_eq!(
        reply(&mut pcp, &table::GET_STATUS, &[]),
        Reply::Status {
            bios_called: false,
            last: TROL_ERR_ROBOT,
            transaction: 13,
            epoch,
        }
    );
}

#[test]
fn finish_wait_replies_only_when_the_arm_is_idle_without_blocking_the_server() {
    let mut pcp = server();
    let r = reply(&mut pcp, &table::JOINT, &[Value::Int(1), Value::Real(1.0)]);
    assert_eq!(r, Reply::Code(Code(0)));
    let request = record::encode(&table::FINISH, &[Value::Int(FINISH_WAIT)]).unwrap();
    // handle() returns at once; the reply comes from poll() once the motion has ended.
    assert_eq!(pcp.handle(&request), Handled::Pending);
    assert!(pcp.is_pending());
    let mut polls = 0;
    let bytes = loop {
        if let Some(b) = pcp.poll() {
            break b;
        }
        polls += 1;
        std::thread::sleep(std::time::Duration::from_millis(1));
    };
    assert_eq!(bytes, [0, 0]);
    assert!(polls > 0, "the motion had ended before the first poll");
    assert!(!pcp.backend_mut().moving().unwrap());
    // A link that breaks while the server waits ends the wait with TROL_ERR_ROBOT.
    reply(&mut pcp, &table::JOINT, &[Value::Int(1), Value::Real(-1.0)]);
    assert_eq!(pcp.handle(&request), Handled::Pending);
    pcp.backend_mut().broken = true;
    assert_eq!(pcp.poll(), Some(TROL_ERR_ROBOT.0.to_le_bytes().to_vec()));
}

/// A Halt from someone else than the host on the line (the pendant, through
/// `handle_aside`) ends the host's Finish with TROL_ERR_HALTED, once, and GetStatus says so;
/// the host's own Halt, a Halt with no motion of the host's under way, or a new motion after
/// it leave Finish as it was.
#[test]
fn a_halt_from_the_pendant_ends_the_hosts_finish_as_halted_once() {
    use trol_proto::application::code::TROL_ERR_HALTED;
    let halt = record::encode(&table::HALT, &[]).unwrap();
    let wait = record::encode(&table::FINISH, &[Value::Int(FINISH_WAIT)]).unwrap();
    let status =
        |pcp: &mut Pcp<Recorder>| reply(pcp, &table::FINISH, &[Value::Int(table::FINISH_STATUS)]);
    let joint = |pcp: &mut Pcp<Recorder>| {
        let r = reply(pcp, &table::JOINT, &[Value::Int(1), Value::Real(0.1)]);
        assert_eq!(r, Reply::Code(Code(0)));
        pcp.backend_mut().hold = true;
    };
    let mut pcp = server();

    // Finish(FINISH_WAIT) pending while the pendant halts.
    joint(&mut pcp);
    assert_eq!(pcp.handle(&wait), Handled::Pending);
    assert_eq!(pcp.poll(), None, "the arm still moves");
    assert_eq!(pcp.handle_aside(&halt), [0, 0]);
    assert_eq!(pcp.poll(), Some(TROL_ERR_HALTED.0.to_le_bytes().to_vec()));
    match reply(&mut pcp, &table::GET_STATUS, &[]) {
        Reply::Status {
            last, bios_called, ..
        } => {
            assert_eq!(last, TROL_ERR_HALTED);
            assert!(bios_called);
        }
        other => panic!("{other:?}"),
    }
    // Once: the next Finish is the ordinary one.
    assert_eq!(status(&mut pcp), Reply::Code(Code(0)));

    // Polled with FINISH_STATUS: 1 while moving, then the halt, once.
    joint(&mut pcp);
    assert_eq!(status(&mut pcp), Reply::Code(Code(1)));
    assert_eq!(pcp.handle_aside(&halt), [0, 0]);
    assert_eq!(status(&mut pcp), Reply::Code(TROL_ERR_HALTED));
    assert_eq!(status(&mut pcp), Reply::Code(Code(0)));

    // The host's own Halt: it knows; Finish answers 0.
    joint(&mut pcp);
    assert_eq!(reply(&mut pcp, &table::HALT, &[]), Reply::Code(Code(0)));
    assert_eq!(status(&mut pcp), Reply::Code(Code(0)));

    // A pendant Halt when the host's motion had already been seen to end: nothing to report.
    joint(&mut pcp);
    pcp.backend_mut().hold = false;
    finish(&mut pcp);
    assert_eq!(pcp.handle_aside(&halt), [0, 0]);
    finish(&mut pcp);

    // A new motion of the host's after the pendant's Halt: its own Finish is its own.
    joint(&mut pcp);
    assert_eq!(pcp.handle_aside(&halt), [0, 0]);
    let r = reply(&mut pcp, &table::JOINT, &[Value::Int(1), Value::Real(-0.1)]);
    assert_eq!(r, Reply::Code(Code(0)));
    finish(&mut pcp);
}
