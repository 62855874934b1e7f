//! `trol c500c`: an A465 on its C500C (docs/c500c.md): first contact that only reads, and
//! the supervised steps that settle the profile's open points on the arm.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand};

/// An A465 on its C500C.
#[derive(Subcommand, Debug)]
pub enum C500c {
    /// First contact: Ctrl-E and two CR, `crosver`, `ash APP` where it does not run yet,
    /// `robotver`, `armstat`, `w0`, `w2`, `speed`, and `exit` (answered y) only where the
    /// probe started ash; nothing that moves the arm or changes a setting. Every byte goes to
    /// --out, also when the probe stops early.
    #[command(after_help = "\
Examples:
  trol c500c probe --controller /dev/ttyUSB0 --out first.txt
  trol sim --c500c &    # a simulated C500C; then:
  trol c500c probe --controller /dev/pts/4 --out first.txt")]
    Probe(ProbeArgs),
    /// A step that settles one open point of the profile on the arm, and writes only what it
    /// saw into --profile. `motion-return` (supervised: the arm moves): with the arm powered
    /// and homed, joint 6 goes by +3 degrees at 5 % speed and back, and the speed setting is
    /// typed back; when ash's prompt came back (as the motion started, or once it had ended)
    /// is read from where w2 puts the arm right then; it asks for `yes` first (--yes: already
    /// confirmed). `pulses` (supervised: the arm moves): each joint in turn by 3 degrees at
    /// 5 % speed and back, `w2` after each; its pulses per degree and where it counts from
    /// (`pulses-per-degree`, `pulses-at-zero`); it asks for `yes` first. `home-pose`
    /// (supervised: the arm moves): ash's `home`, then where the arm stands homed
    /// (`home-joints`), written once you confirm it stands at its home marks (--yes: both
    /// confirmed); a Home is refused until it is set. `world-angles` (reads
    /// only): which reading of the WORLD row's angles puts the flange where TROL's kinematics
    /// put it from the JOINTS row, with the arm standing where the readings differ (a wrist
    /// joint turned). Every byte goes to --out.
    #[command(after_help = "\
Examples:
  trol c500c step motion-return --controller /dev/ttyUSB0 \\
    --profile c500c.toml --out step.txt
  trol c500c step world-angles --controller /dev/ttyUSB0 \\
    --profile c500c.toml --out angles.txt
  trol c500c step pulses --controller /dev/ttyUSB0 \\
    --profile c500c.toml --out pulses.txt
  trol c500c step home-pose --controller /dev/ttyUSB0 \\
    --profile c500c.toml --out home.txt
  trol sim --c500c --homed &    # a simulated C500C; then:
  trol c500c step motion-return --controller /dev/pts/4 \\
    --profile c500c.toml --out step.txt --yes")]
    Step(StepArgs),
    /// The application's location variables (precision points and cartesian locations, as
    /// ash prints them) into a text file on the PC. Reads only; connects as `c500c:` does
    /// (starting `ash APP` where the system shell runs). The `.v3` file itself is not copied:
    /// the console has no public way to read a file out (docs/c500c.md).
    #[command(after_help = "\
Examples:
  trol c500c backup --controller /dev/ttyUSB0 --out cell.locations
  trol c500c restore --controller /dev/ttyUSB0 cell.locations")]
    Backup(BackupArgs),
    /// Write a backup's locations back: first says what it would do (reads only), then,
    /// after `yes` (--yes: already confirmed), sets each cartesian location that differs or
    /// is missing (each read back), creates missing names, and saves (ash's `save`).
    /// Precision points cannot be given from values on a C500C: those that differ are listed,
    /// with the file's pulses, to teach again on the arm. Never moves the arm.
    #[command(after_help = "\
Examples:
  trol c500c restore --controller /dev/ttyUSB0 cell.locations --dry-run
  trol c500c restore --controller /dev/ttyUSB0 cell.locations")]
    Restore(RestoreArgs),
}

/// The console to connect to, as backup and restore share it.
#[derive(Args, Debug)]
pub struct ConsoleArgs {
    /// The front console's serial device, or socket://HOST:PORT (c500c: may lead).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// The C500C profile (its `baud` and `app`; default: 57600 and test).
    #[arg(long, value_name = "FILE")]
    profile: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BackupArgs {
    #[command(flatten)]
    console: ConsoleArgs,
    /// The file to write.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Args, Debug)]
pub struct RestoreArgs {
    #[command(flatten)]
    console: ConsoleArgs,
    /// The backup to restore (written by `trol c500c backup`).
    file: PathBuf,
    /// Only say what it would do.
    #[arg(long)]
    dry_run: bool,
    /// Already confirmed (no question asked).
    #[arg(long)]
    yes: bool,
}

/// The supervised steps.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum StepName {
    /// When ash gives its prompt back after a motion command (`motion-return`).
    MotionReturn,
    /// How the WORLD row's angles compose (`world-angles`; reads only).
    WorldAngles,
    /// Each joint's pulses per degree and where it counts from (`pulses-per-degree`,
    /// `pulses-at-zero`).
    Pulses,
    /// Where ash homes the arm (`home-joints`): a Home, then two readings; written once you
    /// have seen the arm at its home marks.
    HomePose,
}

#[derive(Args, Debug)]
pub struct StepArgs {
    /// The step.
    #[arg(value_enum)]
    step: StepName,
    /// The front console's serial device, or socket://HOST:PORT (c500c: may lead).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// The C500C profile to settle the point in: read where it exists (its other keys kept),
    /// written with what the step saw; left alone where the step saw nothing it could tell.
    #[arg(long, value_name = "FILE")]
    profile: PathBuf,
    /// Where the transcript goes (`> ` sent, `< ` read).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// The person at the arm has confirmed that it is clear to move (no question asked).
    #[arg(long)]
    yes: bool,
    /// Baud rate (the console's: 57600).
    #[arg(long, default_value_t = 57600)]
    baud: u32,
    /// The ash application to move through (the factory one: test).
    #[arg(long, default_value = "test")]
    app: String,
    /// How long to wait for each answer, ms.
    #[arg(long, default_value_t = 10000)]
    wait_ms: u64,
}

#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// The front console's serial device, or socket://HOST:PORT (c500c: may lead).
    #[arg(long, value_name = "DEVICE")]
    controller: String,
    /// Baud rate (the console's: 57600).
    #[arg(long, default_value_t = 57600)]
    baud: u32,
    /// The ash application to read through (the factory one: test).
    #[arg(long, default_value = "test")]
    app: String,
    /// Where the transcript goes (`> ` sent, `< ` read).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// How long to wait for each answer, ms.
    #[arg(long, default_value_t = 3000)]
    wait_ms: u64,
}

/// Run a `trol c500c` command.
pub fn run(c: C500c) -> Result<(), String> {
    match c {
        C500c::Probe(a) => probe(a),
        C500c::Step(a) => step(a),
        C500c::Backup(a) => backup(a),
        C500c::Restore(a) => restore(a),
    }
}

/// Connect as `c500c:` does: reads only.
fn connect(c: &ConsoleArgs) -> Result<trol_c500c::C500cBackend, String> {
    let profile = match &c.profile {
        Some(p) => trol_c500c::Profile::from_file(p).map_err(|e| e.to_string())?,
        None => trol_c500c::Profile::default(),
    };
    let device = c
        .controller
        .strip_prefix(trol_c500c::PREFIX)
        .unwrap_or(&c.controller);
    let settings = trol_port::PortSettings {
        baud: profile.baud,
        ..Default::default()
    };
    let port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    trol_c500c::C500cBackend::connect(port, profile, None).map_err(|e| e.to_string())
}

fn backup(a: BackupArgs) -> Result<(), String> {
    let mut b = connect(&a.console)?;
    let saved = b.backup().map_err(|e| format!("backup: {e}"))?;
    std::fs::write(&a.out, saved.to_text())
        .map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    say!(
        "trol c500c backup: {} location variable(s) of the application {} in {}",
        saved.vars.len(),
        saved.app,
        a.out.display()
    );
    say!(
        "  (the values of its locations; the {}.v3 file itself is not copied: \
         docs/c500c.md, Backup and restore)",
        saved.app
    );
    Ok(())
}

fn restore(a: RestoreArgs) -> Result<(), String> {
    let text = std::fs::read_to_string(&a.file)
        .map_err(|e| format!("cannot read {}: {e}", a.file.display()))?;
    let file = trol_c500c::backend::Backup::parse(&text)
        .map_err(|e| format!("{}: {e}", a.file.display()))?;
    let mut b = connect(&a.console)?;
    let plan = b
        .restore(&file, false)
        .map_err(|e| format!("restore: {e}"))?;
    let show = |r: &trol_c500c::backend::Restored, done: bool| {
        let (set, made) = if done {
            ("written and read back", "created")
        } else {
            ("to write", "to create")
        };
        say!("  as the file has them: {}", list(&r.same));
        say!("  cartesian locations {set}: {}", list(&r.written));
        say!("  names {made}: {}", list(&r.created));
        for (n, p) in &r.to_teach {
            say!(
                "  precision point {n}: teach again on the arm (the file's pulses: {})",
                p.map(|x| x.to_string()).join(" ")
            );
        }
    };
    // What a restore cannot write: said, and the exit status says it (issue 62: a partial
    // restore exited 0).
    let partial = |r: &trol_c500c::backend::Restored| {
        if r.to_teach.is_empty() {
            Ok(())
        } else {
            let names: Vec<&str> = r.to_teach.iter().map(|(n, _)| n.as_str()).collect();
            Err(format!(
                "restore is partial: the precision point(s) {} differ from the file and were \
                 not restored (ash cannot set a precision point's pulses): teach each again on \
                 the arm",
                names.join(", ")
            ))
        }
    };
    say!("trol c500c restore {}:", a.file.display());
    show(&plan, false);
    if a.dry_run {
        return Ok(());
    }
    if plan.written.is_empty() && plan.created.is_empty() {
        return partial(&plan);
    }
    if !a.yes {
        say!("Write these into the application's variables and save? Type yes to go on:");
        let mut answer = String::new();
        let _ = std::io::stdin().read_line(&mut answer);
        if answer.trim() != "yes" {
            return Err("not confirmed: nothing was written (type yes, or give --yes)".into());
        }
    }
    let done = b
        .restore(&file, true)
        .map_err(|e| format!("restore: {e}"))?;
    say!("done:");
    show(&done, true);
    partial(&done)
}

fn list(v: &[String]) -> String {
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

fn step(a: StepArgs) -> Result<(), String> {
    // The profile first: a file that cannot be used stops the step before anything moves.
    let mut profile = if a.profile.exists() {
        trol_c500c::Profile::from_file(&a.profile).map_err(|e| e.to_string())?
    } else {
        trol_c500c::Profile::default()
    };
    let device = a
        .controller
        .strip_prefix(trol_c500c::PREFIX)
        .unwrap_or(&a.controller)
        .to_string();
    let moves = match a.step {
        StepName::MotionReturn => Some(format!(
            "trol c500c step motion-return moves the arm: joint 6 by +{} degrees at {} % speed, \
             then back",
            trol_c500c::probe::STEP_DEG,
            trol_c500c::probe::STEP_SPEED
        )),
        StepName::Pulses => Some(format!(
            "trol c500c step pulses moves the arm: each joint in turn by {} degrees at {} % \
             speed, then back (away from its nearer limit)",
            trol_c500c::probe::STEP_DEG,
            trol_c500c::probe::STEP_SPEED
        )),
        StepName::HomePose => Some(
            "trol c500c step home-pose moves the arm: ash's `home` drives every axis to its \
             home switch (bring the arm near its home position by pendant first)"
                .to_string(),
        ),
        StepName::WorldAngles => None,
    };
    if let Some(what) = moves
        && !a.yes
    {
        say!(
            "{what}, on the C500C at {device}. Make sure nobody and nothing is within its \
             reach and a hand is on the emergency stop. Type yes to go on:"
        );
        let mut answer = String::new();
        let _ = std::io::stdin().read_line(&mut answer);
        if answer.trim() != "yes" {
            return Err("not confirmed: nothing was sent (type yes, or give --yes)".into());
        }
    }
    let settings = trol_port::PortSettings {
        baud: a.baud,
        ..Default::default()
    };
    let mut port = trol_port::open(&device, &settings).map_err(|e| e.to_string())?;
    let wait = Duration::from_millis(a.wait_ms);
    // Each step: what it saw, and whether it settled its key in the profile.
    let (contact, settled) = match a.step {
        StepName::MotionReturn => {
            say!("trol c500c step motion-return: on the C500C at {device}");
            let s = trol_c500c::probe::motion_return_step(port.as_mut(), &a.app, wait);
            profile.motion_return = s.motion_return.or(profile.motion_return);
            (s.contact, s.motion_return.is_some())
        }
        StepName::WorldAngles => {
            say!("trol c500c step world-angles: reading the C500C at {device} (nothing moves)");
            let s = trol_c500c::probe::world_angles_step(port.as_mut(), &a.app, wait);
            if let Some(r) = s.reading {
                profile.world_angles = Some(r.angles);
                profile.tool_rotation = Some(r.frame);
            }
            if let Some(seen) = s.cloc_world_order {
                profile.cloc_world_order = seen;
            }
            (s.contact, s.reading.is_some())
        }
        StepName::HomePose => {
            say!("trol c500c step home-pose: on the C500C at {device}");
            let s = trol_c500c::probe::home_pose_step(port.as_mut(), &a.app, wait);
            let seen = match s.joints {
                Some(q) if a.yes => Some(q),
                Some(q) => {
                    if let Some(f) = s.contact.findings.last() {
                        say!("  {f}");
                    }
                    say!(
                        "Does the arm stand at its home marks (each joint's alignment marks \
                         meet)? Type yes to write home-joints:"
                    );
                    let mut answer = String::new();
                    let _ = std::io::stdin().read_line(&mut answer);
                    (answer.trim() == "yes").then_some(q)
                }
                None => None,
            };
            if let Some(q) = seen {
                // Three decimals, as w2 prints them.
                profile.home_joints = Some(q.map(|v| (v * 1e3).round() / 1e3 + 0.0));
            }
            (s.contact, seen.is_some())
        }
        StepName::Pulses => {
            say!("trol c500c step pulses: on the C500C at {device}");
            let s = trol_c500c::probe::pulses_step(port.as_mut(), &a.app, wait);
            if let Some(rel) = s.pulses {
                // Four decimals, as the step says them.
                profile.pulses_per_degree = Some(rel.per_degree.map(|k| (k * 1e4).round() / 1e4));
                profile.pulses_at_zero = Some(rel.at_zero);
            }
            (s.contact, s.pulses.is_some())
        }
    };
    std::fs::write(&a.out, contact.transcript.text())
        .map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    for f in &contact.findings {
        say!("  {f}");
    }
    say!("  every byte: {}", a.out.display());
    if !settled {
        return Err(format!(
            "nothing settled; {} left as it was",
            a.profile.display()
        ));
    }
    std::fs::write(&a.profile, profile.to_toml())
        .map_err(|e| format!("cannot write {}: {e}", a.profile.display()))?;
    say!("  written to {}", a.profile.display());
    Ok(())
}

fn probe(a: ProbeArgs) -> Result<(), String> {
    let settings = trol_port::PortSettings {
        baud: a.baud,
        ..Default::default()
    };
    let device = a
        .controller
        .strip_prefix(trol_c500c::PREFIX)
        .unwrap_or(&a.controller);
    let mut port = trol_port::open(device, &settings).map_err(|e| e.to_string())?;
    say!("trol c500c probe: reading the C500C on {device} (nothing moves)");
    let contact =
        trol_c500c::probe::first_contact(port.as_mut(), &a.app, Duration::from_millis(a.wait_ms));
    std::fs::write(&a.out, contact.transcript.text())
        .map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    for (cmd, r) in &contact.steps {
        match r {
            Ok(lines) => say!("  {cmd}: {} line(s)", lines.len()),
            Err(e) => say!("  {cmd}: {e}"),
        }
    }
    for f in &contact.findings {
        say!("  {f}");
    }
    say!("  every byte: {}", a.out.display());
    match contact.findings.last() {
        Some(f) if f.starts_with("stopped: ") => Err(f.clone()),
        _ => Ok(()),
    }
}
