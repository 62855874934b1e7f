//! `trol-ros2` (also run as `trol ros2`): one A465 as a ROS 2 node, on any TROL port, without
//! a ROS install (issue 41; docs/ros2.md).
//!
//! It speaks ROS 2's topics and services with their names, types and CDR encoding through
//! ros2-client, on the pure-Rust DDS rustdds, so that neither libtrol nor the Python wheel
//! carries DDS. Under the namespace given:
//!
//! - `joint_states` (sensor_msgs/JointState): the arm's actual joints (`joint_1` ..
//!   `joint_6`, the URDF's names), with velocities from two readings, at `--rate` Hz;
//!   reliable, keep last 10 (ROS 2's default for topics);
//! - `robot_description` (std_msgs/String): the URDF of `trol urdf`, transient local, so a
//!   subscriber that starts later still gets it;
//! - the services `home` and `halt` (std_srvs/Trigger): TROLHome(0) until the arm is homed,
//!   TROLHalt until it stands; `success` only as TROL saw it on the arm, and on failure the
//!   TROL code's name and meaning in `message`.
//!
//! ROS 2's environment is honoured: `ROS_DOMAIN_ID`, and `ROS_LOCALHOST_ONLY=1` or
//! `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` (or `--localhost-only`) keep every packet on
//! 127.0.0.1.

mod action_server;
mod actions;
mod follow;
mod humble;
mod mapping;
mod moveit;
mod msgs;
mod params;
mod replies;
mod rosout;

use std::net::{IpAddr, Ipv4Addr};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use clap::Parser;
use ros2_client::{
    Context, MessageTypeName, Name, NodeName, NodeOptions, QosProfile,
    qos::{Durability, History, WhenFull},
};
use rustdds::DomainParticipantBuilder;
use trol::{PosMode, Robot, Tag};
use trol_cli::common::Conn;

use msgs::{
    FollowFeedback, FollowGoal, FollowResult, GripperFeedback, GripperGoal, GripperResult, Header,
    JointState, Time, TriggerRequest, TriggerResponse,
};

/// The joints' names, as `trol urdf` names them.
pub(crate) const JOINTS: [&str; 6] = [
    "joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6",
];

/// The joints' names with `prefix` (`--prefix`) before each.
pub(crate) fn joint_names(prefix: &str) -> [String; 6] {
    JOINTS.map(|j| format!("{prefix}{j}"))
}
/// The node's name (in its namespace).
const NODE: &str = "trol_a465";
/// The longest a Home may take before the service says it failed (six axes group by group
/// at the homing speed take well under a minute on an A465; assumption with room).
const HOME_LIMIT: Duration = Duration::from_secs(180);
/// How often requests (goals, cancels, halts) are taken between two readings of the arm.
const SERVE_EVERY: Duration = Duration::from_millis(2);
/// How often a wait asks whether the arm still moves (TROL's own poll).
const POLL: Duration = trol::POLL;

#[derive(Parser, Debug)]
#[command(
    name = "trol-ros2",
    about = "One A465 as a ROS 2 node: joint_states, robot_description, and the services home \
             and halt, on any TROL port, without a ROS install (docs/ros2.md)",
    after_help = "Examples:\n  trol ros2                                   # the embedded simulator\n  \
                  ROS_LOCALHOST_ONLY=1 trol ros2 --namespace arm1 --time-scale 5\n  \
                  trol ros2 --config trol.cfg --domain 7     # the controller trol.cfg names"
)]
struct Args {
    #[command(flatten)]
    conn: Conn,
    /// The node's namespace (`arm1`, or `/cell/arm1`); its topics and services live under it.
    #[arg(long, default_value = "/")]
    namespace: String,
    /// Put before every joint and link name (`arm1_`: `arm1_joint_1` in joint_states, in the
    /// goals it takes, and in robot_description), so one MoveIt can address each arm of a
    /// cell; letters, digits and `_`.
    #[arg(long, default_value = "", value_parser = prefix)]
    prefix: String,
    /// The ROS 2 distribution of the peers (default: $ROS_DISTRO, else jazzy): Kilted and
    /// Rolling read FollowJointTrajectory's feedback in control_msgs 6.3's layout.
    #[arg(long, value_enum)]
    distro: Option<Distro>,
    /// Write MoveIt's files for this node into DIR and end (the URDF and SRDF with
    /// --prefix's names, joint_limits.yaml within what TROL accepts, kinematics.yaml,
    /// moveit_controllers.yaml for --namespace's action, move_group.launch.py); no arm, no DDS.
    #[arg(long, value_name = "DIR")]
    write_config: Option<std::path::PathBuf>,
    /// Reject a trajectory goal while one runs (by default a new goal replaces the running
    /// one, as ROS 2's joint_trajectory_controller does: the arm is halted where it is, the
    /// old goal ends canceled, and the new trajectory starts there).
    #[arg(long)]
    one_goal: bool,
    /// The ROS 2 domain (default: $ROS_DOMAIN_ID, else 0).
    #[arg(long, value_parser = clap::value_parser!(u16).range(0..=232))]
    domain: Option<u16>,
    /// How often joint_states is published, Hz.
    #[arg(long, default_value_t = 50.0, value_parser = rate)]
    rate: f64,
    /// Keep every packet on 127.0.0.1 (also: ROS_LOCALHOST_ONLY=1 or
    /// ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST).
    #[arg(long)]
    localhost_only: bool,
    /// More log on stderr: -v what TROL does, -vv the controller's lines (else $RUST_LOG,
    /// else warnings).
    #[arg(short, long, action = clap::ArgAction::Count)]
    verbose: u8,
}

/// A ROS 2 distribution, for the layouts that differ between them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Distro {
    Humble,
    Jazzy,
    Kilted,
    Rolling,
}

impl Distro {
    /// `--distro`, else `$ROS_DISTRO` (set by a ROS 2 install's setup script), else Jazzy.
    fn pick(given: Option<Distro>) -> Result<Distro, String> {
        use clap::ValueEnum;
        if let Some(d) = given {
            return Ok(d);
        }
        match std::env::var("ROS_DISTRO") {
            Ok(v) if !v.trim().is_empty() => Distro::from_str(v.trim(), true).map_err(|_| {
                format!(
                    "ROS_DISTRO `{v}` is not one this node knows (humble, jazzy, kilted, \
                     rolling): give --distro"
                )
            }),
            _ => Ok(Distro::Jazzy),
        }
    }

    /// Whether FollowJointTrajectory's feedback has control_msgs 6.3's two indices.
    pub(crate) fn feedback_has_indices(self) -> bool {
        matches!(self, Distro::Kilted | Distro::Rolling)
    }
}

fn prefix(s: &str) -> Result<String, String> {
    if s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !s.starts_with(|c: char| c.is_ascii_digit())
    {
        Ok(s.to_string())
    } else {
        Err(format!(
            "`{s}` is not a name prefix: letters, digits and `_`, not starting with a digit"
        ))
    }
}

fn rate(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.1..=500.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a rate from 0.1 to 500 Hz")),
    }
}

/// Set by SIGTERM or SIGHUP: the node halts the arm and ends, as on Ctrl-C (a second such
/// signal ends it at once).
static TERMINATED: std::sync::LazyLock<Arc<std::sync::atomic::AtomicBool>> =
    std::sync::LazyLock::new(|| Arc::new(std::sync::atomic::AtomicBool::new(false)));

/// Catch SIGTERM and SIGHUP into [`TERMINATED`].
fn catch_termination() {
    use signal_hook::consts::{SIGHUP, SIGTERM};
    for signal in [SIGTERM, SIGHUP] {
        // The shutdown first: it ends the process only when the flag was set before.
        let caught =
            signal_hook::flag::register_conditional_shutdown(signal, 143, TERMINATED.clone())
                .and_then(|_| signal_hook::flag::register(signal, TERMINATED.clone()));
        if let Err(e) = caught {
            crate::warn_ros!(
                "trol-ros2: signal {signal} will end the node without halting the arm: {e}"
            );
        }
    }
}

/// Whether the node is asked to end (Ctrl-C, SIGTERM, SIGHUP).
fn ending() -> bool {
    use std::sync::atomic::Ordering::SeqCst;
    trol_cli::common::interrupted().load(SeqCst) || TERMINATED.load(SeqCst)
}

fn main() {
    trol_cli::common::catch_interrupts();
    catch_termination();
    let args = Args::parse();
    // The DDS's own log (discovery, locators) would drown what the arm does. Its UDP
    // listener's only error is one at the end, leaving a multicast group a loopback-only
    // participant never joined (rustdds 0.15 leaves it whether joined or not): two ERROR
    // lines on every clean exit, which say nothing.
    trol_cli::common::init_logging_quieting(
        args.verbose,
        "rustdds=error,rustdds::network::udp_listener=off,ros2_client=error",
    );
    if let Err(e) = run(args) {
        crate::warn_ros!("trol-ros2: {e}");
        std::process::exit(1);
    }
}

/// The namespace as ROS 2 writes it: a leading `/`, no trailing one (`/` for none).
fn namespace(ns: &str) -> Result<String, String> {
    let trimmed = ns.trim_matches('/');
    let full = format!("/{trimmed}");
    let ok = trimmed.is_empty()
        || trimmed.split('/').all(|part| {
            part.chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && part.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        });
    if ok {
        Ok(full)
    } else {
        Err(format!(
            "--namespace `{ns}`: ROS 2 names are letters, digits and `_`, each part starting \
             with a letter or `_`"
        ))
    }
}

fn localhost_only(flag: bool) -> bool {
    flag || std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v.trim() == "1")
        || std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .is_ok_and(|v| v.trim().eq_ignore_ascii_case("LOCALHOST"))
}

fn domain(flag: Option<u16>) -> Result<u16, String> {
    if let Some(d) = flag {
        return Ok(d);
    }
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v
            .trim()
            .parse::<u16>()
            .ok()
            .filter(|d| *d <= 232)
            .ok_or_else(|| format!("ROS_DOMAIN_ID `{v}` is not a domain from 0 to 232")),
        _ => Ok(0),
    }
}

/// The URDF with `prefix` before every link's and joint's name, and so before every
/// reference to a link (a joint's parent and child).
fn prefixed_urdf(urdf: &str, prefix: &str) -> String {
    if prefix.is_empty() {
        return urdf.to_string();
    }
    let mut out = String::with_capacity(urdf.len() + 64 * prefix.len());
    let mut rest = urdf;
    // `<link name="`, `<joint name="`, `link="` (parent, child), and the SRDF's link
    // references: each name after them.
    let marks = [
        "<link name=\"",
        "<joint name=\"",
        " link=\"",
        " base_link=\"",
        " tip_link=\"",
        " link1=\"",
        " link2=\"",
        " parent_link=\"",
        "<mimic joint=\"",
    ];
    while let Some((at, mark)) = marks
        .iter()
        .filter_map(|m| rest.find(m).map(|i| (i, *m)))
        .min_by_key(|(i, _)| *i)
    {
        let end = at + mark.len();
        out.push_str(&rest[..end]);
        out.push_str(prefix);
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// How often (in joint_states ticks) the gripper's gap is read when no gripper goal runs.
const GRIP_EVERY: u64 = 25;

/// The gripper's gap, m (TROLGetGripper), or None where the controller cannot read it.
fn read_gap(robot: &Mutex<Robot>) -> Option<f64> {
    robot
        .lock()
        .ok()?
        .gripper()
        .ok()
        .map(|g| g.opening_mm / 1000.0)
}

/// The URDF the node publishes and writes: the A465 with its gripper's fingers
/// (trol_a465::urdf::urdf_with_gripper: `gripper_joint`'s value is the fingers' gap in metres,
/// 0 .. 0.05, as GripperCommand's `position`, so that MoveIt's gripper controller can name
/// it), with `prefix`.
pub(crate) fn described(prefix: &str) -> String {
    prefixed_urdf(&trol_a465::urdf::urdf_with_gripper(), prefix)
}

/// The SRDF beside [`described`], with `prefix`.
pub(crate) fn semantic(prefix: &str) -> String {
    prefixed_urdf(&trol_a465::urdf::srdf_with_gripper(), prefix)
}

/// How long one reading of the arm's joints takes: the slowest of three (0 when they fail:
/// the loop says so when it reads).
fn read_time(robot: &Mutex<Robot>) -> f64 {
    let mut worst: f64 = 0.0;
    for _ in 0..3 {
        let t = Instant::now();
        let ok = robot
            .lock()
            .map(|mut r| r.position(Tag::Joint, PosMode::Actual).is_ok())
            .unwrap_or(false);
        if !ok {
            return 0.0;
        }
        worst = worst.max(t.elapsed().as_secs_f64());
    }
    worst
}

/// The rate joint_states keeps: the one asked, or what reads of `read_s` s each allow with a
/// fifth of each period left for requests.
fn honest_rate(asked: f64, read_s: f64) -> f64 {
    if read_s <= 0.0 {
        return asked;
    }
    asked.min(0.8 / read_s).max(0.1)
}

/// A rate for words: whole where it is, else to a tenth (0.7 Hz, 50 Hz).
fn trim_rate(hz: f64) -> String {
    if (hz - hz.round()).abs() < 0.05 {
        format!("{}", hz.round())
    } else {
        format!("{hz:.1}")
    }
}

/// How long a starting node listens for another that serves its names (discovery on a
/// loopback takes well under a second; an assumption with room).
const DISCOVERY_WAIT: Duration = Duration::from_secs(2);

/// A DDS request topic as ROS 2 names the service (`rq/arm1/homeRequest`: `/arm1/home`).
fn ros_name(topic: &str) -> String {
    let name = topic.strip_prefix("rq").unwrap_or(topic);
    let name = name.strip_suffix("Request").unwrap_or(name);
    name.strip_suffix("/_action/send_goal")
        .unwrap_or(name)
        .to_string()
}

/// Whether, within `wait`, another participant shows a reader of one of `requests` (a
/// server of that service): the topic, and who it is.
fn served_elsewhere(
    participant: &rustdds::DomainParticipant,
    requests: &[String],
    wait: Duration,
) -> Option<(String, String)> {
    use rustdds::RTPSEntity;
    let own = participant.guid().prefix;
    let until = Instant::now() + wait;
    loop {
        let found = participant.discovered_readers().into_iter().find(|r| {
            requests.contains(&r.subscription_topic_data.topic_name)
                && r.reader_proxy.remote_reader_guid.prefix != own
        });
        if let Some(r) = found {
            let guid = r.reader_proxy.remote_reader_guid.to_bytes();
            let who = format!(
                "participant {}",
                guid[..12]
                    .iter()
                    .map(|b| format!("{b:02x}"))
                    .collect::<String>()
            );
            return Some((r.subscription_topic_data.topic_name.clone(), who));
        }
        if Instant::now() >= until {
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The TROL error in words for a service's `message`: its code's name, and what TROL said.
pub(crate) fn words(e: &trol::Error) -> String {
    format!("{} ({}): {e}", e.code().0, e.code())
}

fn run(args: Args) -> Result<(), String> {
    let ns = namespace(&args.namespace)?;
    let joints = joint_names(&args.prefix);
    if let Some(dir) = &args.write_config {
        let files = moveit::files(
            &joints,
            &ns,
            &described(&args.prefix),
            &semantic(&args.prefix),
        );
        moveit::write(dir, &files)?;
        trol_cli::say!(
            "trol-ros2: wrote {} for MoveIt into {}",
            files
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            dir.display()
        );
        return Ok(());
    }
    let distro = Distro::pick(args.distro)?;
    let domain = domain(args.domain)?;
    let local = localhost_only(args.localhost_only);

    let mut builder = DomainParticipantBuilder::new(domain);
    if local {
        builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    let participant = builder
        .build()
        .map_err(|e| format!("cannot join ROS 2 domain {domain}: {e:?}"))?;
    // Another node serving these names would take the same goals and move its arm too:
    // this one does not start then, and touches no arm.
    let node_name = NodeName::new(&ns, NODE).map_err(|e| format!("node name: {e:?}"))?;
    let served: Vec<String> = [
        "home",
        "halt",
        "follow_joint_trajectory/_action/send_goal",
        "gripper_cmd/_action/send_goal",
    ]
    .iter()
    .map(|p| replies::Service::new(&ns, p, &node_name).map(|s| s.request))
    .collect::<Result<_, _>>()?;
    if let Some((topic, who)) = served_elsewhere(&participant, &served, DISCOVERY_WAIT) {
        return Err(format!(
            "another node already serves {} on ROS 2 domain {domain} ({who}): start this one \
             with another --namespace, or stop that one; nothing was served and no arm was \
             touched",
            ros_name(&topic)
        ));
    }
    let (robot, cfg) = args.conn.robot()?;
    let robot = Arc::new(Mutex::new(robot));
    let context = Context::from_domain_participant(participant)
        .map_err(|e| format!("cannot start ROS 2: {e:?}"))?;
    // Its words go to /rosout too (rosout.rs); it declares no parameters (it runs no
    // ros2-client spinner, whose parameter services would take the participant's status
    // events replies.rs reads).
    let mut node = context
        .new_node(node_name.clone(), NodeOptions::new().enable_rosout(true))
        .map_err(|e| format!("cannot create the node: {e:?}"))?;
    rosout::attach(&node);
    // Which clients' reply readers this node's writers have matched: a reply waits for its
    // client's (replies.rs).
    let mut matches = replies::Matches::new(context.domain_participant());
    let service = |path: &str| replies::Service::new(&ns, path, &node_name);
    let action_services = |action: &str| actions::ActionServices::new(&ns, action, &node_name);
    let mut home_replies = replies::Replies::new(service("home")?);
    let mut halt_replies = replies::Replies::new(service("halt")?);

    let name = |base: &str| Name::new(&ns, base).map_err(|e| format!("{base}: {e:?}"));
    let topic_qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    let latched_qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 });
    let service_qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    let create = |e| format!("ROS 2: {e:?}");

    let states_topic = node
        .create_topic(
            &name("joint_states")?,
            MessageTypeName::new("sensor_msgs", "JointState"),
            &topic_qos,
        )
        .map_err(create)?;
    let states = node
        .create_publisher::<JointState>(&states_topic, None)
        .map_err(create)?;
    let description_topic = node
        .create_topic(
            &name("robot_description")?,
            MessageTypeName::new("std_msgs", "String"),
            &latched_qos,
        )
        .map_err(create)?;
    let description = node
        .create_publisher::<String>(&description_topic, None)
        .map_err(create)?;
    description
        .publish(described(&args.prefix))
        .map_err(|e| format!("robot_description: {e:?}"))?;
    // Services answer each client in its middleware's mapping (mapping.rs); their reply
    // writers are the DDS's own, in a publisher of their own.
    let dds = context.domain_participant();
    let writers = dds
        .create_publisher(&rustdds::QosPolicies::from(&service_qos))
        .map_err(|e| format!("ROS 2: {e:?}"))?;
    let vendors = matches.vendors();
    let trigger = "std_srvs::srv::dds_::Trigger";
    let home = mapping::AnyServer::<TriggerRequest, TriggerResponse>::new(
        &mut node,
        &dds,
        &writers,
        &service("home")?,
        trigger,
        &service_qos,
        vendors.clone(),
    )?;
    let halt = mapping::AnyServer::<TriggerRequest, TriggerResponse>::new(
        &mut node,
        &dds,
        &writers,
        &service("halt")?,
        trigger,
        &service_qos,
        vendors.clone(),
    )?;
    let action_qos = actions::action_qos();
    fn place<'a>(
        node: &'a mut ros2_client::Node,
        node_name: &'a NodeName,
        participant: &'a rustdds::DomainParticipant,
        writers: &'a rustdds::Publisher,
        vendors: &mapping::SharedVendors,
    ) -> action_server::Place<'a> {
        action_server::Place {
            node,
            node_name,
            participant,
            writers,
            vendors: vendors.clone(),
        }
    }
    let follow = action_server::AnyActionServer::<FollowGoal, FollowResult, FollowFeedback>::new(
        place(&mut node, &node_name, &dds, &writers, &vendors),
        &ns,
        "follow_joint_trajectory",
        ("control_msgs", "FollowJointTrajectory"),
        &action_qos,
    )?;
    let gripper =
        action_server::AnyActionServer::<GripperGoal, GripperResult, GripperFeedback>::new(
            place(&mut node, &node_name, &dds, &writers, &vendors),
            &ns,
            "gripper_cmd",
            ("control_msgs", "GripperCommand"),
            &action_qos,
        )?;
    // The embedded simulator runs its clock `time_scale` times faster: the desired path of a
    // trajectory is read on the arm's clock.
    let mut trajectories = actions::Served::follow(
        if cfg.port == "sim" {
            cfg.time_scale
        } else {
            1.0
        },
        joints.clone(),
        distro,
        !args.one_goal,
        action_services("follow_joint_trajectory")?,
    );

    // The rate joint_states can keep: a controller whose position read takes longer than a
    // period (a C500: about a second) gets the rate its reads allow, said at start.
    let read_s = read_time(&robot);
    let rate = honest_rate(args.rate, read_s);
    let prefix = if ns == "/" { String::new() } else { ns.clone() };
    rosout::info(&format!(
        "trol-ros2: node {prefix}/{NODE} on ROS 2 domain {domain}{}, arm on port {}: \
         {prefix}/joint_states at {} Hz{}, {prefix}/robot_description, services {prefix}/home \
         and {prefix}/halt, actions {prefix}/follow_joint_trajectory and \
         {prefix}/gripper_cmd",
        if local { " (localhost only)" } else { "" },
        cfg.port,
        trim_rate(rate),
        if rate < args.rate {
            format!(
                " (asked {} Hz: a position read takes {:.0} ms on this controller)",
                trim_rate(args.rate),
                read_s * 1e3
            )
        } else {
            String::new()
        }
    ));

    // The parameters, read-only, say how the node was started (`ros2 param list`).
    let mut parameters = params::Services::new(
        params::Place {
            node: &mut node,
            node_name: &node_name,
            ns: &ns,
            participant: &dds,
            writers: &writers,
            qos: &service_qos,
            vendors: vendors.clone(),
        },
        node_params(&args, &cfg.port, rate, distro),
    )?;
    let mut grips = actions::Served::gripper(action_services("gripper_cmd")?);
    // Humble's peers read the node's discovery message only in their own layout (humble.rs):
    // written once every entity of the node is made.
    let humble_discovery = if distro == Distro::Humble {
        let d = humble::Discovery::new(&dds, &writers)?;
        d.publish(&context.participant_entities_info())?;
        Some(d)
    } else {
        None
    };
    let period = Duration::from_secs_f64(1.0 / rate);
    let mut next = Instant::now();
    let mut last: Option<([f64; 6], Instant)> = None;
    // Halts served: a Home during which one came is not reported homed.
    let halts = Arc::new(std::sync::atomic::AtomicU64::new(0));
    // Homes under way: their answers come back on a channel, so joint_states keeps going.
    let (done_tx, done_rx) = mpsc::channel::<(mapping::Asker, TriggerResponse)>();
    let mut reading_failed = false;
    // The gripper's gap for joint_states: read at start, then every GRIP_EVERY ticks and
    // at every tick while a gripper goal runs (None: this controller cannot read it).
    let gripper_joint = format!("{}gripper_joint", args.prefix);
    let mut gap_m = read_gap(&robot);
    let mut ticks: u64 = 0;
    while !ending() {
        // The arm is read, and the actions follow it, once a period; requests are taken
        // every SERVE_EVERY between, so a goal or a halt waits for no period.
        let tick = Instant::now() >= next;
        if tick {
            next += period;
            let now = Instant::now();
            if next <= now {
                // Behind (a slow line): start again from now, not in a burst.
                next = now + period;
            }
            let read = robot
                .lock()
                .map_err(|_| "the arm's connection was poisoned".to_string())?
                .position(Tag::Joint, PosMode::Actual);
            match read {
                Ok(loc) => {
                    reading_failed = false;
                    let q = loc.to_array6();
                    let now = Instant::now();
                    let velocity = match last {
                        Some((p, at)) if now > at => {
                            let dt = (now - at).as_secs_f64();
                            (0..6).map(|i| (q[i] - p[i]) / dt).collect()
                        }
                        _ => vec![0.0; 6],
                    };
                    last = Some((q, now));
                    ticks += 1;
                    if gap_m.is_some() && (ticks.is_multiple_of(GRIP_EVERY) || grips.is_running()) {
                        gap_m = read_gap(&robot);
                    }
                    let (mut name, mut position, mut velocity) =
                        (joints.to_vec(), q.to_vec(), velocity);
                    if let Some(gap) = gap_m {
                        name.push(gripper_joint.clone());
                        position.push(gap);
                        velocity.push(0.0);
                    }
                    let msg = JointState {
                        header: Header {
                            stamp: Time::now(),
                            frame_id: String::new(),
                        },
                        name,
                        position,
                        velocity,
                        effort: Vec::new(),
                    };
                    if let Err(e) = states.publish(msg) {
                        tracing::warn!("joint_states: {e:?}");
                    }
                }
                Err(e) => {
                    // Said once per run of failures; publishing resumes when readings do.
                    if !reading_failed {
                        crate::warn_ros!("trol-ros2: cannot read the arm: {e}");
                    }
                    reading_failed = true;
                    last = None;
                }
            }
        }
        // Services.
        matches.refresh();
        while let Some((id, _)) = mapping::next(|| home.receive_request()) {
            let robot = robot.clone();
            let done = done_tx.clone();
            let halts = halts.clone();
            std::thread::spawn(move || {
                let _ = done.send((id, home_arm(&robot, &halts)));
            });
        }
        while let Some((id, _)) = mapping::next(|| halt.receive_request()) {
            halts.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            let answer = match robot.lock() {
                Ok(mut r) => match r.halt() {
                    Ok(()) => TriggerResponse {
                        success: true,
                        message: "the arm stands".into(),
                    },
                    Err(e) => TriggerResponse {
                        success: false,
                        message: words(&e),
                    },
                },
                Err(_) => TriggerResponse {
                    success: false,
                    message: "the arm's connection was poisoned".into(),
                },
            };
            halt_replies.push(id, answer, Instant::now());
        }
        parameters.serve(&matches);
        matches.refresh();
        let actual = if tick { last.map(|(q, _)| q) } else { None };
        let arm = actions::Arm {
            robot: &robot,
            actual,
            halts: &halts,
        };
        trajectories.serve(&follow, &arm, tick, &matches);
        grips.serve(&gripper, &arm, tick, &matches);
        while let Ok((id, answer)) = done_rx.try_recv() {
            home_replies.push(id, answer, Instant::now());
        }
        let now = Instant::now();
        halt_replies.flush(
            now,
            |s| matches.hear(s),
            |id, answer| {
                if let Err(e) = halt.send_response(id, answer) {
                    tracing::warn!("halt's response: {e}");
                }
            },
        );
        home_replies.flush(
            now,
            |s| matches.hear(s),
            |id, answer| {
                if let Err(e) = home.send_response(id, answer) {
                    tracing::warn!("home's response: {e}");
                }
            },
        );
        std::thread::sleep(next.saturating_duration_since(now).min(SERVE_EVERY));
    }
    // Humble's peers learn the node is gone (ros2-client says so in its own layout).
    if let Some(d) = &humble_discovery {
        let gid = context.participant_entities_info().gid();
        let _ = d.publish(&ros2_client::entities_info::ParticipantEntitiesInfo::new(
            gid,
            Vec::new(),
        ));
    }
    // Leaving: an arm that still moves by this node's doing is stopped, and seen standing.
    // The connection stays locked from here on: a Home's thread must not start a transaction
    // that the end of the process would cut in half (the controller would be left answering
    // nobody, in the way of the next program's first call).
    let Ok(mut r) = robot.lock() else {
        return Ok(());
    };
    if r.is_moving().unwrap_or(false) {
        match r.halt() {
            Ok(()) => rosout::said(
                rosout::LogLevel::Info,
                "trol-ros2: ending: the arm was moving; it is halted and stands",
            ),
            Err(e) => crate::warn_ros!(
                "trol-ros2: ending: the arm was moving and its halt failed: {}",
                words(&e)
            ),
        }
    }
    // The lock is never given back: the node's DDS entities still end properly (its peers
    // learn it is gone), and no other thread of it talks to the controller again.
    std::mem::forget(r);
    Ok(())
}

/// The node's parameters: how it was started.
fn node_params(args: &Args, port: &str, rate: f64, distro: Distro) -> params::Params {
    use params::{Declared, Value};
    params::Params(vec![
        Declared {
            name: "port",
            value: Value::Text(port.to_string()),
            description: "the arm's port (sim, a serial device, tcp:, rapl:, mars:, c500c:)",
            option: "--port",
        },
        Declared {
            name: "rate",
            value: Value::Double(rate),
            description: "how often joint_states is published, Hz (what the controller's \
                          reads allow, where that is less than --rate)",
            option: "--rate",
        },
        Declared {
            name: "prefix",
            value: Value::Text(args.prefix.clone()),
            description: "what every joint's and link's name starts with",
            option: "--prefix",
        },
        Declared {
            name: "distro",
            value: Value::Text(format!("{distro:?}").to_lowercase()),
            description: "the ROS 2 distribution whose message layouts the node writes",
            option: "--distro (or ROS_DISTRO)",
        },
        Declared {
            name: "one_goal",
            value: Value::Bool(args.one_goal),
            description: "true: a trajectory goal that comes while one runs is refused; \
                          false: it replaces the running one",
            option: "--one-goal",
        },
        Declared {
            name: "use_sim_time",
            value: Value::Bool(false),
            description: "the node's stamps are the machine's clock, as the arm's motion is",
            option: "nothing (the arm keeps real time)",
        },
    ])
}

/// TROLHome(0), then wait until the arm is done with the connection free between polls (a
/// halt gets through), as TROLHome does: success only once the controller's Finish saw it
/// done (a real controller's backend ends a Home that left the arm unhomed with a code), and
/// never when a halt came meanwhile (the axes after it may not be homed).
fn home_arm(robot: &Mutex<Robot>, halts: &std::sync::atomic::AtomicU64) -> TriggerResponse {
    let halts_before = halts.load(std::sync::atomic::Ordering::SeqCst);
    let fail = |message: String| TriggerResponse {
        success: false,
        message,
    };
    let sent = match robot.lock() {
        Ok(mut r) => r.call(&trol::table::HOME, &[trol::Value::Int(0)]),
        Err(_) => return fail("the arm's connection was poisoned".into()),
    };
    if let Err(e) = sent {
        return fail(words(&e));
    }
    let until = Instant::now() + HOME_LIMIT;
    loop {
        let moving = match robot.lock() {
            Ok(mut r) => r.is_moving(),
            Err(_) => return fail("the arm's connection was poisoned".into()),
        };
        match moving {
            Ok(false) => break,
            Ok(true) if Instant::now() < until => std::thread::sleep(POLL),
            Ok(true) => {
                return fail(format!(
                    "the arm still moves after {} s: call halt",
                    HOME_LIMIT.as_secs()
                ));
            }
            Err(e) => return fail(words(&e)),
        }
    }
    if halts.load(std::sync::atomic::Ordering::SeqCst) != halts_before {
        return fail("halted during homing: the axes may not be homed; call home again".into());
    }
    TriggerResponse {
        success: true,
        message: "the arm is homed".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_states_keep_the_rate_the_controller_s_reads_allow() {
        assert_eq!(honest_rate(50.0, 0.002), 50.0);
        // A C500's read of about 1.2 s: well under a hertz, said as it is.
        let r = honest_rate(50.0, 1.2);
        assert!((r - 0.8 / 1.2).abs() < 1e-9);
        assert_eq!(trim_rate(r), "0.7");
        assert_eq!(trim_rate(50.0), "50");
        // Reads that failed do not lower it (the loop says why it cannot read).
        assert_eq!(honest_rate(50.0, 0.0), 50.0);
    }

    #[test]
    fn a_prefix_names_every_link_and_joint_and_every_reference_stays_whole() {
        let plain = trol_a465::urdf::urdf_with_gripper();
        let urdf = described("arm1_");
        let names = |kind: &str, text: &str| -> Vec<String> {
            text.split(&format!("<{kind} name=\""))
                .skip(1)
                .map(|s| s.split('"').next().unwrap().to_string())
                .collect()
        };
        let links = names("link", &urdf);
        let joints = names("joint", &urdf);
        assert_eq!(links.len(), names("link", &plain).len());
        assert!(
            links.iter().chain(&joints).all(|n| n.starts_with("arm1_")),
            "{links:?} {joints:?}"
        );
        for j in joint_names("arm1_") {
            assert!(joints.contains(&j), "{j} missing from {joints:?}");
        }
        // Every parent and child names a link of this URDF.
        for r in urdf.split(" link=\"").skip(1) {
            let l = r.split('"').next().unwrap();
            assert!(links.iter().any(|x| x == l), "{l} is no link of {links:?}");
        }
        // The fingers' mimic joint names the prefixed gripper_joint; the SRDF's references
        // are all prefixed.
        assert!(
            urdf.contains("<mimic joint=\"arm1_gripper_joint\""),
            "{urdf}"
        );
        let srdf = semantic("arm1_");
        for r in srdf.split("link=\"").skip(1) {
            let l = r.split('"').next().unwrap();
            assert!(links.iter().any(|x| x == l), "{l} is no link of {links:?}");
        }
        for r in srdf.split("<link name=\"").skip(1) {
            let l = r.split('"').next().unwrap();
            assert!(links.iter().any(|x| x == l), "{l} is no link of {links:?}");
        }
        // Materials keep their names.
        assert!(urdf.contains("<material name=\"body\">"));
        assert_eq!(prefixed_urdf(&plain, ""), plain);
    }

    #[test]
    fn namespaces_are_written_as_ros_2_writes_them_and_bad_ones_are_refused() {
        assert_eq!(namespace("/").unwrap(), "/");
        assert_eq!(namespace("").unwrap(), "/");
        assert_eq!(namespace("arm1").unwrap(), "/arm1");
        assert_eq!(namespace("/cell/arm_2/").unwrap(), "/cell/arm_2");
        for bad in ["1arm", "arm-1", "a b", "cell//arm"] {
            let e = namespace(bad).unwrap_err();
            assert!(e.contains("--namespace"), "{e}");
        }
    }

    #[test]
    fn rates_outside_what_the_node_can_keep_are_refused() {
        assert_eq!(rate("50").unwrap(), 50.0);
        for bad in ["0", "-5", "nan", "1000", "fast"] {
            assert!(rate(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_domain_flag_wins_and_is_bounded_as_ros_2_bounds_it() {
        assert_eq!(domain(Some(7)).unwrap(), 7);
        assert!(Args::try_parse_from(["trol-ros2", "--domain", "233"]).is_err());
        assert!(Args::try_parse_from(["trol-ros2", "--domain", "232"]).is_ok());
    }
}
