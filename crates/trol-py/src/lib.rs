//! `trol._trol`: the native half of TROL for Python, a thin skin over the Rust API
//! (`trol::Robot`). The Python half (`python/trol/`) holds the exceptions and the value
//! types; this module raises and returns them.
//!
//! Every call that talks to the controller releases the GIL (`Python::detach`), so other
//! Python threads run meanwhile. `finish()` waits by polling TROLFinish(FINISH_STATUS), with
//! the connection's lock released between polls (so `halt()` from another thread gets
//! through) and Python's signals checked at each turn (Ctrl-C halts the arm and raises
//! KeyboardInterrupt). No panic crosses into Python: PyO3 turns one into PanicException.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use trol::code::{Code, TROL_ERR_ARG_RANGE, TROL_ERR_COMM};
use trol::{
    ArgKind, CommandDef, Config, Error, LocName, Location, PosMode, Reply, SimSettings, Tag, Value,
};

/// How often `finish()` asks whether the arm still moves.
const POLL: Duration = Duration::from_millis(10);

/// An exception of `trol._errors`, built with `args`.
fn exception<'py, A>(py: Python<'py>, class: &str, args: A) -> PyErr
where
    A: IntoPyObject<'py, Target = PyTuple, Output = Bound<'py, PyTuple>>,
{
    let made = py
        .import("trol._errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| {
            let args = args.into_pyobject(py).map_err(Into::into)?;
            c.call1(args)
        });
    match made {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

fn argument_error(py: Python<'_>, message: String) -> PyErr {
    exception(py, "ArgumentError", (message, TROL_ERR_ARG_RANGE.0))
}

fn setup_error(py: Python<'_>, message: String) -> PyErr {
    exception(py, "SetupError", (message, TROL_ERR_COMM.0))
}

/// A failed call, with the link's last layer-2 code when the link failed.
struct Failure {
    error: Error,
    last_comm: Option<u16>,
}

fn to_py(py: Python<'_>, f: Failure) -> PyErr {
    let message = f.error.to_string();
    let code = f.error.code().0;
    match f.error {
        Error::Refused { command, name, .. } => exception(
            py,
            "RefusedError",
            (message, code, command, name.unwrap_or_default()),
        ),
        Error::Argument(_) => exception(py, "ArgumentError", (message, code)),
        Error::Link { .. } => exception(py, "LinkError", (message, code, f.last_comm)),
        Error::BadReply { .. } => exception(py, "BadReplyError", (message, code)),
        Error::Setup(trol::SetupError::Incompatible { ours, theirs, .. }) => {
            exception(py, "IncompatibleError", (message, code, ours, theirs))
        }
        Error::Setup(_) => exception(py, "SetupError", (message, code)),
        // A kind of failure added to the Rust API later: the base class, with its code.
        _ => exception(py, "TrolError", (message, code)),
    }
}

/// A connection to a TROL controller: the embedded simulator (port "sim"), a serial device,
/// a pseudo-terminal, or socket://HOST:PORT.
#[pyclass(frozen, module = "trol._trol")]
struct Robot {
    inner: Mutex<Option<trol::Robot>>,
}

impl Robot {
    fn new(robot: trol::Robot) -> Robot {
        Robot {
            inner: Mutex::new(Some(robot)),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Option<trol::Robot>> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Run `f` on the connection with the GIL released.
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut trol::Robot) -> trol::Result<T> + Send,
    ) -> PyResult<T> {
        let result = py.detach(|| {
            let mut guard = self.lock();
            let Some(robot) = guard.as_mut() else {
                return Err(None);
            };
            f(robot).map_err(|error| {
                let last_comm = match error {
                    Error::Link { .. } => robot.last_comm_error().map(|e| e.code()),
                    _ => None,
                };
                Some(Failure { error, last_comm })
            })
        });
        result.map_err(|f| match f {
            Some(f) => to_py(py, f),
            None => setup_error(py, "the robot is closed; open a new one".into()),
        })
    }

    fn position(&self, py: Python<'_>, tag: Tag, actual: bool) -> PyResult<Location> {
        let mode = if actual {
            PosMode::Actual
        } else {
            PosMode::Commanded
        };
        self.with(py, move |r| r.position(tag, mode))
    }
}

/// Any sequence of real numbers (list, tuple, numpy array of a real dtype) as f64s. Text,
/// bytes (a sequence of small ints to Python), booleans, complex numbers and numpy arrays of
/// another dtype are refused: each would become a motion nobody meant (`mi(b"abcdef")` was an
/// MI of 97..102 rad).
fn floats(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    use pyo3::types::{PyBool, PyByteArray, PyBytes, PyFloat, PyInt, PyString};
    let type_name = |o: &Bound<'_, PyAny>| {
        o.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default()
    };
    let bad = |got: String| {
        argument_error(
            py,
            format!("{what}: expected a sequence of up to 6 real numbers, got {got}"),
        )
    };
    if obj.is_instance_of::<PyString>()
        || obj.is_instance_of::<PyBytes>()
        || obj.is_instance_of::<PyByteArray>()
    {
        return Err(bad(type_name(obj)));
    }
    // Only an ordered sequence: a dict would give its keys (`mi({2: 0.1})` turned joint 1
    // by 2 rad), a set its items in no order, a generator whatever it yields; a range is
    // counting, not angles (issue 67, item 6).
    // SAFETY: PySequence_Check only reads the object's type slots; `obj` is a live object.
    let ordered = unsafe { pyo3::ffi::PySequence_Check(obj.as_ptr()) } == 1;
    if !ordered || obj.is_instance_of::<pyo3::types::PyRange>() {
        return Err(exception(
            py,
            "ArgumentTypeError",
            (
                format!(
                    "{what}: expected an ordered sequence of up to 6 real numbers (a list, a \
                     tuple or a numpy array), got {}",
                    type_name(obj)
                ),
                TROL_ERR_ARG_RANGE.0,
            ),
        ));
    }
    // A buffer of bytes or integers (memoryview, array.array): its items are small ints
    // to Python, and `mi(memoryview(b"abcdef"))` was an MI of 97..102 rad. Only a buffer of
    // reals is taken.
    for attr in ["format", "typecode"] {
        if let Ok(code) = obj.getattr(attr).and_then(|f| f.extract::<String>())
            && !matches!(
                code.trim_start_matches(['@', '=', '<', '>', '!']),
                "d" | "f" | "e"
            )
        {
            return Err(bad(format!("a {} of format {code:?}", type_name(obj))));
        }
    }
    // numpy: the array's (or scalar's) dtype kind: f float, i int, u unsigned.
    let real_dtype = |o: &Bound<'_, PyAny>| -> Option<Result<(), String>> {
        let dtype = o.getattr("dtype").ok()?;
        let kind: String = dtype.getattr("kind").ok()?.extract().ok()?;
        Some(if matches!(kind.as_str(), "f" | "i" | "u") {
            Ok(())
        } else {
            Err(format!(
                "a numpy array of dtype {}",
                dtype.str().map(|s| s.to_string()).unwrap_or(kind)
            ))
        })
    };
    if let Some(Err(got)) = real_dtype(obj) {
        return Err(bad(got));
    }
    let items = obj.try_iter().map_err(|_| bad(type_name(obj)))?;
    let mut out = Vec::new();
    for item in items {
        let item = item?;
        let real = if item.is_instance_of::<PyBool>() {
            false
        } else if item.is_instance_of::<PyFloat>() || item.is_instance_of::<PyInt>() {
            true
        } else {
            matches!(real_dtype(&item), Some(Ok(())))
        };
        if !real {
            return Err(bad(format!("an element of type {}", type_name(&item))));
        }
        out.push(item.extract::<f64>().map_err(|_| bad(type_name(&item)))?);
    }
    Ok(out)
}

/// A number argument of type `T` (`kind` says which, for the message). A bool is refused:
/// Python counts it as an int, and `joint(True, 0.1)` moved joint 1.
fn number<'py, T: pyo3::conversion::FromPyObjectOwned<'py>>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    what: &str,
    kind: &str,
) -> PyResult<T> {
    let got = if obj.is_instance_of::<pyo3::types::PyBool>() {
        "a bool".to_string()
    } else {
        match obj.extract::<T>() {
            Ok(v) => return Ok(v),
            Err(_) => obj
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default(),
        }
    };
    Err(argument_error(
        py,
        format!("{what}: expected {kind}, got {got}"),
    ))
}

/// A whole number argument (not a bool).
fn whole<'py>(py: Python<'py>, obj: &Bound<'py, PyAny>, what: &str) -> PyResult<u16> {
    number(py, obj, what, "a whole number")
}

/// A real number argument (an int or a float; not a bool).
fn real<'py>(py: Python<'py>, obj: &Bound<'py, PyAny>, what: &str) -> PyResult<f64> {
    number(py, obj, what, "a number")
}

fn is_precision(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    let class = py.import("trol._types")?.getattr("Precision")?;
    obj.is_instance(&class)
}

/// A motion target: a location name (str), a `trol.Precision`, or up to 6 cartesian values.
enum Target {
    Name(String),
    Location(Location),
}

fn target(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Target> {
    if let Ok(name) = obj.extract::<String>() {
        return Ok(Target::Name(name));
    }
    if is_precision(py, obj)? {
        let counts = obj.extract::<Vec<i32>>()?;
        return Ok(Target::Location(Location::Prec(counts)));
    }
    Ok(Target::Location(Location::Cart(floats(py, obj, "target")?)))
}

fn value_object<'py>(
    py: Python<'py>,
    class: &str,
    values: Vec<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let cls = py.import("trol._types")?.getattr(class)?;
    cls.call1(PyTuple::new(py, values)?)
}

fn location_object<'py>(py: Python<'py>, loc: Location) -> PyResult<Bound<'py, PyAny>> {
    match loc {
        Location::Cart(v) => value_object(py, "Pose", v),
        Location::Joint(v) => value_object(py, "Joints", v),
        Location::Prec(c) => {
            let cls = py.import("trol._types")?.getattr("Precision")?;
            cls.call1(PyTuple::new(py, c)?)
        }
    }
}

/// A ``trol.Gripper`` of GetGripper's answer.
fn gripper_object<'py>(py: Python<'py>, g: trol::Gripper) -> PyResult<Bound<'py, PyAny>> {
    let (holding, known): (Option<String>, bool) = match g.held {
        trol::Held::Nothing => (None, true),
        trol::Held::Object(name) => (Some(name), true),
        _ => (None, false),
    };
    let cls = py.import("trol._types")?.getattr("Gripper")?;
    cls.call1((g.opening_mm, holding, known))
}

/// A trajectory's waypoints from Python: an iterable of `(time, joints)` pairs (seconds from
/// the start; six joint angles in radians).
fn waypoints(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<trol::Waypoint>> {
    let bad = |k: usize, why: &str| {
        argument_error(
            py,
            format!("{what}: waypoint {k}: {why} (a waypoint is (time_s, six joint angles))"),
        )
    };
    if obj.is_instance_of::<pyo3::types::PyString>() {
        return Err(argument_error(
            py,
            format!("{what}: expected (time, joints) pairs, got a string"),
        ));
    }
    let mut out = Vec::new();
    for (i, item) in obj.try_iter()?.enumerate() {
        let k = i + 1;
        let item = item?;
        let (t, q): (Bound<'_, PyAny>, Bound<'_, PyAny>) =
            item.extract().map_err(|_| bad(k, "not a pair"))?;
        if t.is_instance_of::<pyo3::types::PyBool>() {
            return Err(bad(k, "its time is a bool"));
        }
        let time = t
            .extract::<f64>()
            .map_err(|_| bad(k, "its time is not a number"))?;
        let joints = floats(py, &q, &format!("{what}: waypoint {k}"))?;
        let joints: [f64; 6] = joints
            .try_into()
            .map_err(|v: Vec<f64>| bad(k, &format!("{} joint angles, not 6", v.len())))?;
        out.push(trol::Waypoint { time, joints });
    }
    Ok(out)
}

/// A Python argument for an argument of `kind`.
fn arg_value(py: Python<'_>, name: &str, kind: ArgKind, obj: &Bound<'_, PyAny>) -> PyResult<Value> {
    let bad = |what: &str| argument_error(py, format!("`{name}`: expected {what}"));
    Ok(match kind {
        ArgKind::Int { .. } if obj.is_instance_of::<pyo3::types::PyBool>() => {
            return Err(bad("a whole number 0..255, not a bool"));
        }
        ArgKind::Int { .. } => Value::Int(
            obj.extract::<u8>()
                .map_err(|_| bad("a whole number 0..255"))?,
        ),
        ArgKind::Choice(options) => {
            if let Ok(word) = obj.extract::<String>() {
                let c = options
                    .iter()
                    .find(|c| {
                        word.eq_ignore_ascii_case(c.word) || word.eq_ignore_ascii_case(c.constant)
                    })
                    .ok_or_else(|| bad("one of its words"))?;
                Value::Int(c.value)
            } else {
                Value::Int(
                    obj.extract::<u8>()
                        .map_err(|_| bad("one of its words or values"))?,
                )
            }
        }
        ArgKind::Straight => Value::Flag(obj.extract::<bool>().map_err(|_| bad("True or False"))?),
        ArgKind::Name => {
            let s = obj
                .extract::<String>()
                .map_err(|_| bad("a location name"))?;
            Value::Name(LocName::new(&s).map_err(|e| argument_error(py, e.to_string()))?)
        }
        ArgKind::Real if obj.is_instance_of::<pyo3::types::PyBool>() => {
            return Err(bad("a number, not a bool"));
        }
        ArgKind::Real => Value::Real(obj.extract::<f64>().map_err(|_| bad("a number"))?),
        ArgKind::Path { .. } => Value::Path(waypoints(py, obj, name)?),
        ArgKind::Loc { tags, .. } => {
            if tags.contains(&Tag::Prec) && is_precision(py, obj)? {
                Value::Loc(Location::Prec(obj.extract::<Vec<i32>>()?))
            } else if tags.contains(&Tag::Cart) {
                Value::Loc(Location::Cart(floats(py, obj, name)?))
            } else if tags.contains(&Tag::Joint) {
                Value::Loc(Location::Joint(floats(py, obj, name)?))
            } else {
                Value::Loc(Location::Prec(
                    obj.extract::<Vec<i32>>()
                        .map_err(|_| bad("encoder counts"))?,
                ))
            }
        }
    })
}

fn reply_object<'py>(py: Python<'py>, reply: Reply) -> PyResult<Bound<'py, PyAny>> {
    Ok(match reply {
        Reply::Code(v) => v.0.into_pyobject(py)?.into_any(),
        Reply::Reals { values, .. } => values.into_pyobject(py)?.into_any(),
        Reply::Position(loc) => location_object(py, loc)?,
        Reply::Status {
            bios_called, last, ..
        } => (bios_called, last.0).into_pyobject(py)?.into_any(),
        Reply::Version { protocol, kind } => (protocol, kind).into_pyobject(py)?.into_any(),
        Reply::Gripper(g) => gripper_object(py, g)?,
        Reply::Codes(codes) => {
            let d = pyo3::types::PyDict::new(py);
            for c in codes {
                d.set_item(c.value, (c.name, c.meaning))?;
            }
            d.into_any()
        }
        Reply::Bytes { value, bytes } => (value.0, PyBytes::new(py, &bytes))
            .into_pyobject(py)?
            .into_any(),
        // A reply form added to the core later: its bytes, as for an added command.
        other => {
            let bytes = other.encode();
            (other.value().0, PyBytes::new(py, &bytes[2..]))
                .into_pyobject(py)?
                .into_any()
        }
    })
}

/// A new connection, checked (with ``check``) as InitTROL(1) checks it: one GetStatus, then
/// the controller's protocol version ([`trol::check_server`]).
fn connected(py: Python<'_>, connect: trol::Connect, check: bool) -> PyResult<Robot> {
    let fail = |error| {
        to_py(
            py,
            Failure {
                error,
                last_comm: None,
            },
        )
    };
    // The one connect path (trol::Connect); `check=False` only for a test double.
    let connect = if check {
        connect
    } else {
        connect.without_check()
    };
    let mut robot = py.detach(|| connect.connect()).map_err(fail)?;
    if let Some(notice) = robot.take_notice() {
        // Said once, as a warning the program can filter or turn into an error.
        let warnings = py.import("warnings")?;
        warnings.call_method1("warn", (format!("trol: {notice}"),))?;
    }
    Ok(Robot::new(robot))
}

#[pymethods]
impl Robot {
    /// Connect: "sim" starts the embedded simulated controller (``time_scale`` times real
    /// time); otherwise a serial device, a pseudo-terminal or socket://HOST:PORT at ``baud``.
    /// With ``check`` (the default) the server must answer and speak this library's protocol
    /// version, as InitTROL(1) checks: SetupError otherwise, saying what to do.
    #[staticmethod]
    #[pyo3(signature = (port = "sim", *, baud = None, time_scale = None, check = true))]
    fn open(
        py: Python<'_>,
        port: &str,
        baud: Option<u32>,
        time_scale: Option<f64>,
        check: bool,
    ) -> PyResult<Robot> {
        if port == "sim" {
            let scale = time_scale.unwrap_or(1.0);
            if !(scale.is_finite() && scale > 0.0) {
                return Err(argument_error(
                    py,
                    format!("time_scale {scale} must be a number above 0"),
                ));
            }
            let settings = SimSettings {
                time_scale: scale,
                ..SimSettings::default()
            };
            return connected(py, trol::Connect::sim(settings), check);
        }
        if time_scale.is_some() {
            return Err(argument_error(
                py,
                "time_scale applies to port \"sim\" only".into(),
            ));
        }
        connected(
            py,
            trol::Connect::port(port).baud(baud.unwrap_or(9600)),
            check,
        )
    }

    /// Connect as trol.cfg says (``path``, else $TROL_CONFIG, else ./trol.cfg), as InitTROL
    /// reads it; the embedded simulator gets the file's settings. ``check`` as for open.
    #[staticmethod]
    #[pyo3(signature = (path = None, *, check = true))]
    fn from_config(py: Python<'_>, path: Option<PathBuf>, check: bool) -> PyResult<Robot> {
        let cfg = match &path {
            Some(p) => Config::from_file(p),
            None => Config::load(),
        }
        .map_err(|e| setup_error(py, e.to_string()))?;
        connected(py, trol::Connect::config(&cfg), check)
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        py: Python<'_>,
        _kind: &Bound<'_, PyAny>,
        _value: &Bound<'_, PyAny>,
        _traceback: &Bound<'_, PyAny>,
    ) -> bool {
        self.close(py);
        false
    }

    /// Close the connection (an embedded controller stops). Later calls raise SetupError.
    fn close(&self, py: Python<'_>) {
        let robot = py.detach(|| self.lock().take());
        drop(robot);
    }

    /// TROLHome: home one axis (1..6) or all (0); returns when homing is done.
    #[pyo3(signature = (axis = 0))]
    fn home(&self, py: Python<'_>, axis: u16) -> PyResult<()> {
        self.with(py, move |r| r.home(axis))
    }

    /// TROLReady: to the READY pose.
    fn ready(&self, py: Python<'_>) -> PyResult<()> {
        self.with(py, |r| r.ready())
    }

    /// TROLMove (a location name) or TROLMoveII (a Pose or up to 6 cartesian values, or a
    /// trol.Precision).
    #[pyo3(signature = (target, straight = false))]
    fn r#move(&self, py: Python<'_>, target: &Bound<'_, PyAny>, straight: bool) -> PyResult<()> {
        match self::target(py, target)? {
            Target::Name(n) => self.with(py, move |r| r.move_to(&n, straight)),
            Target::Location(l) => self.with(py, move |r| r.move_ii(&l, straight)),
        }
    }

    /// TROLAppro / TROLApproII: approach ``target`` displaced by ``offset`` (up to 6 values:
    /// x y z mm, yaw pitch roll rad) in its tool frame.
    #[pyo3(signature = (target, offset, straight = false))]
    fn appro(
        &self,
        py: Python<'_>,
        target: &Bound<'_, PyAny>,
        offset: &Bound<'_, PyAny>,
        straight: bool,
    ) -> PyResult<()> {
        let offset = floats(py, offset, "offset")?;
        match self::target(py, target)? {
            Target::Name(n) => self.with(py, move |r| r.appro(&n, &offset, straight)),
            Target::Location(l) => self.with(py, move |r| r.appro_ii(&l, &offset, straight)),
        }
    }

    /// TROLDepart: move by ``offset`` in the tool frame.
    #[pyo3(signature = (offset, straight = false))]
    fn depart(&self, py: Python<'_>, offset: &Bound<'_, PyAny>, straight: bool) -> PyResult<()> {
        let offset = floats(py, offset, "offset")?;
        self.with(py, move |r| r.depart(&offset, straight))
    }

    /// TROLJog: move the tool by dx [dy [dz]] mm in the world frame.
    #[pyo3(signature = (delta, straight = false))]
    fn jog(&self, py: Python<'_>, delta: &Bound<'_, PyAny>, straight: bool) -> PyResult<()> {
        let delta = floats(py, delta, "delta")?;
        self.with(py, move |r| r.jog(&delta, straight))
    }

    /// TROLJoint: move joint ``number`` (1..6) by ``radians``.
    fn joint(
        &self,
        py: Python<'_>,
        number: &Bound<'_, PyAny>,
        radians: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let number = whole(py, number, "joint: number")?;
        let radians = real(py, radians, "joint: radians")?;
        self.with(py, move |r| r.joint(number, radians))
    }

    /// TROLMA: all joints to absolute angles (radians; missing ones 0).
    fn ma(&self, py: Python<'_>, joints: &Bound<'_, PyAny>) -> PyResult<()> {
        let q = floats(py, joints, "joints")?;
        self.with(py, move |r| r.ma(&q))
    }

    /// TROLTrajectory: one motion through ``points``, each ``(time_s, joints)`` (seconds
    /// from the start, increasing; six joint angles in radians). Returns ``"timed"`` (the
    /// simulated A465, a MARS 8: at the given times; refused with BIOS_TOO_FAST before
    /// anything moves where they ask more than the arm has) or ``"untimed"`` (one joint move
    /// to each waypoint at the speed setting). Wait with ``finish()``.
    fn trajectory(&self, py: Python<'_>, points: &Bound<'_, PyAny>) -> PyResult<&'static str> {
        let path = waypoints(py, points, "points")?;
        let timing = self.with(py, move |r| r.trajectory(&path))?;
        Ok(match timing {
            trol::Timing::Timed => "timed",
            trol::Timing::Untimed => "untimed",
        })
    }

    /// TROLMI: all joints by increments (radians).
    fn mi(&self, py: Python<'_>, deltas: &Bound<'_, PyAny>) -> PyResult<()> {
        let q = floats(py, deltas, "deltas")?;
        self.with(py, move |r| r.mi(&q))
    }

    /// TROLSpeed: percent of the maximum speed (1..150).
    fn speed(&self, py: Python<'_>, percent: &Bound<'_, PyAny>) -> PyResult<()> {
        let percent = whole(py, percent, "speed: percent")?;
        self.with(py, move |r| r.speed(percent))
    }

    /// TROLGrip: the fingers to ``mm`` (0..50), at full force.
    fn grip(&self, py: Python<'_>, mm: &Bound<'_, PyAny>) -> PyResult<()> {
        let mm = whole(py, mm, "grip: mm")?;
        self.with(py, move |r| r.grip(mm))
    }

    /// TROLOpen: open the gripper with ``force`` percent (1..100).
    #[pyo3(signature = (force = 50))]
    fn open_gripper(&self, py: Python<'_>, force: u16) -> PyResult<()> {
        self.with(py, move |r| r.open_gripper(force))
    }

    /// TROLClose: close the gripper with ``force`` percent (1..100).
    #[pyo3(signature = (force = 50))]
    fn close_gripper(&self, py: Python<'_>, force: u16) -> PyResult<()> {
        self.with(py, move |r| r.close_gripper(force))
    }

    /// TROLHalt: stop all motion.
    fn halt(&self, py: Python<'_>) -> PyResult<()> {
        self.with(py, |r| r.halt())
    }

    /// TROLSetToolTransform: where the tool tip is in the tool frame (up to 6 values).
    fn set_tool(&self, py: Python<'_>, pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let tool = floats(py, pose, "pose")?;
        self.with(py, move |r| r.set_tool_transform(&tool))
    }

    /// TROLFinish(FINISH_STATUS): whether the arm or the gripper still moves.
    fn is_moving(&self, py: Python<'_>) -> PyResult<bool> {
        self.with(py, |r| r.is_moving())
    }

    /// Wait until all motion is done, polling FINISH_STATUS with the GIL and the connection
    /// released between polls. ``timeout`` (seconds): raise trol.TimeoutError after it (the
    /// arm keeps moving). Ctrl-C halts the arm and raises KeyboardInterrupt.
    #[pyo3(signature = (timeout = None))]
    fn finish(&self, py: Python<'_>, timeout: Option<f64>) -> PyResult<()> {
        let deadline = match timeout {
            // A timeout beyond what the clock can add (1e300 s) is no limit at all.
            Some(t) if t.is_finite() && t >= 0.0 => Duration::try_from_secs_f64(t)
                .ok()
                .and_then(|d| Instant::now().checked_add(d)),
            Some(t) => {
                return Err(argument_error(
                    py,
                    format!("timeout {t} must be a number >= 0"),
                ));
            }
            None => None,
        };
        loop {
            // Signals first: a Ctrl-C that came while this process was held up (a loaded
            // machine) is reported even if the arm has ended its motion since.
            if let Err(interrupt) = py.check_signals() {
                // Stop the arm before the exception goes up; report the interrupt either way.
                let _ = self.with(py, |r| r.halt());
                return Err(interrupt);
            }
            if !self.is_moving(py)? {
                // One more look: a Ctrl-C during that last poll is still this wait's.
                py.check_signals()?;
                return Ok(());
            }
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return Err(exception(
                    py,
                    "TimeoutError",
                    (
                        format!(
                            "the arm still moves after {} s",
                            timeout.unwrap_or_default()
                        ),
                        TROL_ERR_COMM.0,
                    ),
                ));
            }
            py.detach(|| std::thread::sleep(POLL));
        }
    }

    /// TROLGetPosition(POS_JOINT): the joint angles, commanded or ``actual``.
    #[pyo3(signature = (actual = false))]
    fn joints<'py>(&self, py: Python<'py>, actual: bool) -> PyResult<Bound<'py, PyAny>> {
        location_object(py, self.position(py, Tag::Joint, actual)?)
    }

    /// TROLGetPosition(POS_CART): the tool's pose, commanded or ``actual``.
    #[pyo3(signature = (actual = false))]
    fn pose<'py>(&self, py: Python<'py>, actual: bool) -> PyResult<Bound<'py, PyAny>> {
        location_object(py, self.position(py, Tag::Cart, actual)?)
    }

    /// TROLGetPosition(POS_PREC): the encoder counts, commanded or ``actual``.
    #[pyo3(signature = (actual = false))]
    fn precision<'py>(&self, py: Python<'py>, actual: bool) -> PyResult<Bound<'py, PyAny>> {
        location_object(py, self.position(py, Tag::Prec, actual)?)
    }

    /// TROLHere: store where the arm is (commanded) under ``name``: ``form`` ``"cart"`` (the
    /// default), ``"joint"`` or ``"prec"`` (a precision point; its name starts with ``#``).
    #[pyo3(signature = (name, form = "cart"))]
    fn here(&self, py: Python<'_>, name: String, form: &str) -> PyResult<()> {
        let tag = match form {
            "cart" => Tag::Cart,
            "joint" => Tag::Joint,
            "prec" => Tag::Prec,
            other => {
                return Err(argument_error(
                    py,
                    format!("form {other:?}: expected \"cart\", \"joint\" or \"prec\""),
                ));
            }
        };
        self.with(py, move |r| r.here(&name, tag))
    }

    /// TROLDefine: store ``location`` under ``name``: a ``trol.Pose`` (or six cartesian
    /// values), a ``trol.Joints`` or a ``trol.Precision`` (whose name starts with ``#``).
    fn define(&self, py: Python<'_>, name: String, location: &Bound<'_, PyAny>) -> PyResult<()> {
        let loc = if is_precision(py, location)? {
            Location::Prec(location.extract::<Vec<i32>>()?)
        } else if location.is_instance(&py.import("trol._types")?.getattr("Joints")?)? {
            Location::Joint(floats(py, location, "location")?)
        } else {
            Location::Cart(floats(py, location, "location")?)
        };
        if loc.num_dims() != 6 {
            return Err(argument_error(
                py,
                format!("location: six values, not {}", loc.num_dims()),
            ));
        }
        self.with(py, move |r| r.define(&name, &loc))
    }

    /// TROLDeleteLocation: forget the location ``name`` (trol.RefusedError with
    /// ``TROL_ERR_LOCATION`` if there is none).
    fn delete_location(&self, py: Python<'_>, name: String) -> PyResult<()> {
        self.with(py, move |r| r.delete_location(&name))
    }

    /// TROLSaveLocations: keep the location table across a restart (the simulator writes its
    /// locations file).
    fn save_locations(&self, py: Python<'_>) -> PyResult<()> {
        self.with(py, |r| r.save_locations())
    }

    /// TROLListLocations: the controller's table as a dict, name to ``trol.Pose``,
    /// ``trol.Joints`` or ``trol.Precision``, sorted by name.
    fn locations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let all = self.with(py, |r| r.locations())?;
        let d = pyo3::types::PyDict::new(py);
        for (name, loc) in all {
            d.set_item(name, location_object(py, loc)?)?;
        }
        Ok(d)
    }

    /// TROLGetGripper: a ``trol.Gripper``: the fingers' opening (mm) and what they hold, to
    /// check a grasp.
    fn gripper<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = self.with(py, |r| r.gripper())?;
        gripper_object(py, g)
    }

    /// TROLGetStatus: (whether the last CAT1/CAT2 command called the BIOS, its value or the
    /// TROL code that kept it from being called).
    fn status(&self, py: Python<'_>) -> PyResult<(bool, i16)> {
        self.with(py, |r| r.status().map(|(b, c)| (b, c.0)))
    }

    /// TROLGetStatus in full: (bios_called, last_code, transaction, epoch). The manual's
    /// method after a failed call: ``n = robot.last_transaction()`` first, then this; if its
    /// transaction is ``n``, the status is the failed call's. The epoch changes when the
    /// controller restarts.
    fn status_record(&self, py: Python<'_>) -> PyResult<(bool, i16, u8, u16)> {
        self.with(py, |r| {
            r.status_record()
                .map(|s| (s.bios_called, s.last.0, s.transaction, s.epoch))
        })
    }

    /// The number of the last request this connection sent (0..255). Take it at once after
    /// the call that failed: every request takes a number, status()'s too.
    fn last_transaction(&self, py: Python<'_>) -> PyResult<u8> {
        self.with(py, |r| Ok(r.last_transaction()))
    }

    /// TROLGetVersion, checked: (the protocol version, what drives the arm). Raises
    /// ``trol.SetupError`` for a controller that speaks another protocol than this library.
    fn version(&self, py: Python<'_>) -> PyResult<(u16, String)> {
        self.with(py, |r| r.check_version().map(|v| (v.protocol, v.kind)))
    }

    /// A return value's name and meaning as this connection's controller names it (its
    /// BIOS codes come with the version check, TROLGetCodes): ``-1 (BIOS_NOT_HOMED): ...``.
    fn describe(&self, py: Python<'_>, code: i16) -> PyResult<String> {
        let codes = self.with(py, |r| Ok(r.codes()))?;
        Ok(describe_with(code, codes))
    }

    /// The controller's BIOS codes (TROLGetCodes): ``{value: (name, meaning)}``.
    fn codes(&self, py: Python<'_>) -> PyResult<std::collections::BTreeMap<i16, (String, String)>> {
        let codes = self.with(py, |r| r.get_codes())?;
        Ok(codes
            .into_iter()
            .map(|c| (c.value, (c.name, c.meaning)))
            .collect())
    }

    /// TROLSetWatchdog: the controller halts the arm when no call arrives for ``seconds``
    /// (0.1 .. 25; 0 turns it off). Every call feeds it, and so do ``finish()``'s polls.
    fn set_watchdog(&self, py: Python<'_>, seconds: f64) -> PyResult<()> {
        if !(0.0..=25.0).contains(&seconds) {
            return Err(argument_error(
                py,
                format!("set_watchdog: {seconds} s is outside 0 .. 25 s"),
            ));
        }
        let limit = std::time::Duration::from_secs_f64(seconds);
        self.with(py, move |r| r.set_watchdog(limit))
    }

    /// TROLSetRepeats: how often a request whose reply was lost is sent again, marked as a
    /// repeat, so that it runs exactly once (0..10; 0 is the manual's behaviour: the call
    /// fails and ``status()`` tells whether it ran). Without it: 2 to a controller that
    /// remembers its last request, 0 to one that speaks only the manual's protocol.
    fn set_repeats(&self, py: Python<'_>, repeats: &Bound<'_, PyAny>) -> PyResult<()> {
        let n = whole(py, repeats, "set_repeats: repeats")?;
        if n > 10 {
            return Err(argument_error(
                py,
                format!("set_repeats: {n} is outside 0 .. 10"),
            ));
        }
        self.with(py, move |r| {
            r.set_repeats(n as u8);
            Ok(())
        })
    }

    /// How often a request whose reply was lost is sent again (``set_repeats``).
    fn repeats(&self, py: Python<'_>) -> PyResult<u8> {
        self.with(py, |r| Ok(r.repeats()))
    }

    /// Know the commands described in a TOML file (docs/extending.md), for ``call``.
    fn add_commands(&self, py: Python<'_>, path: PathBuf) -> PyResult<Vec<String>> {
        let defs = trol::described::load(&path).map_err(|e| setup_error(py, e))?;
        let names = defs.iter().map(|d| d.name.to_string()).collect();
        self.with(py, move |r| {
            defs.into_iter()
                .try_for_each(|d| match r.catalog().get(d.code) {
                    Some(known) if *known == d => Ok(()),
                    _ => r.add_command(d),
                })
        })?;
        Ok(names)
    }

    /// Call any command the connection knows, built-in or added, by name (``"TROLForwardKin"``
    /// or ``"forwardkin"``), with its arguments in the description's order. Returns the
    /// return value (CAT1), a list of floats (a float vector), a Pose / Joints / Precision,
    /// or (value, bytes).
    #[pyo3(signature = (name, *args))]
    fn call<'py>(
        &self,
        py: Python<'py>,
        name: &str,
        args: &Bound<'py, PyTuple>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let def: CommandDef = {
            let guard = py.detach(|| {
                self.lock()
                    .as_ref()
                    .map(|r| r.catalog().find(name).copied())
            });
            match guard {
                None => {
                    return Err(setup_error(
                        py,
                        "the robot is closed; open a new one".into(),
                    ));
                }
                Some(None) => {
                    return Err(argument_error(
                        py,
                        format!("no command named {name}; add_commands() describes new ones"),
                    ));
                }
                Some(Some(d)) => d,
            }
        };
        if args.len() != def.args.len() {
            return Err(PyTypeError::new_err(format!(
                "{} takes {} arguments ({}), {} given",
                def.name,
                def.args.len(),
                def.args
                    .iter()
                    .map(|a| a.name)
                    .collect::<Vec<_>>()
                    .join(", "),
                args.len()
            )));
        }
        let mut values = Vec::with_capacity(args.len());
        for (a, obj) in def.args.iter().zip(args.iter()) {
            values.push(arg_value(py, a.name, a.kind, &obj)?);
        }
        let reply = self.with(py, move |r| r.call(&def, &values))?;
        reply_object(py, reply)
    }

    /// TransSR: send a request's bytes, return the reply's bytes (unchecked).
    fn transact<'py>(&self, py: Python<'py>, request: Vec<u8>) -> PyResult<Bound<'py, PyBytes>> {
        let reply = self.with(py, move |r| r.transact_raw(&request))?;
        Ok(PyBytes::new(py, &reply))
    }

    /// For benchmarks: ``n`` TROLSpeed calls made from Rust, in seconds (docs/performance.md).
    fn _rust_loop(&self, py: Python<'_>, n: u32, percent: u16) -> PyResult<f64> {
        self.with(py, move |r| {
            let t = Instant::now();
            for _ in 0..n {
                r.speed(percent)?;
            }
            Ok(t.elapsed().as_secs_f64())
        })
    }
}

/// A return value's name and meaning: ``-1 (BIOS_NOT_HOMED): the arm must be homed first``.
#[pyfunction]
fn describe(code: i16) -> String {
    describe_with(code, trol::default_codes())
}

fn describe_with(code: i16, codes: &trol::CodeTable) -> String {
    let c = Code(code);
    match c.meaning(codes) {
        Some(m) => format!("{}: {m}", c.describe(codes)),
        None => c.describe(codes),
    }
}

#[pymodule]
fn _trol(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Robot>()?;
    m.add_function(wrap_pyfunction!(describe, m)?)?;
    Ok(())
}
