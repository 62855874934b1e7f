//! The RAPL-II commands the simulated C500 runs (c500-rapl.md §1.4), on the simulated
//! A465, with their answers in the variant's forms.

use super::*;

impl C500 {
    pub(super) fn execute(&mut self, line: &str, now: f64) {
        self.log.push(line.to_string());
        let (word, rest) = match line.split_once(' ') {
            Some((w, r)) => (w.trim(), r.trim()),
            None => (line, ""),
        };
        let args: Vec<&str> = rest
            .split([',', ' '])
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = args
            .iter()
            .map(|a| a.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        let motion = matches!(
            word,
            "MOVE"
                | "MOVES"
                | "APPRO"
                | "DEPART"
                | "JOINT"
                | "MA"
                | "MI"
                | "JOG"
                | "READY"
                | "HOME"
        );
        if motion && self.limp {
            return self.refuse(37);
        }
        if motion && self.arm.is_moving(now) {
            // A second motion waits for the first to end (RW's reading, c500-rapl.md §1.1.7).
            self.waiting = Some(Waiting::Motion(line.to_string()));
            return;
        }
        let mm = self.frames.mm.unwrap_or(1.0);
        match (word, nums.as_deref()) {
            ("NOHELP", _) => {
                self.help = false;
                self.ok("")
            }
            ("HELP", _) => {
                self.help = true;
                self.ok("")
            }
            ("SPEED", Some([p])) if (1.0..=100.0).contains(p) => {
                self.arm.set_speed(*p);
                self.ok("")
            }
            ("READY", _) => {
                let c = self.arm.ready(now);
                self.motion_answer(c, now)
            }
            ("HOME", _) => {
                let c = self.arm.home(0, now);
                self.motion_answer(c, now)
            }
            ("MOVE" | "MOVES", _) if args.len() == 1 => match self.target(args[0]) {
                Some(t) => {
                    let c = self.arm.move_to(t, word == "MOVES", now);
                    self.motion_answer(c, now)
                }
                None => self.refuse(35),
            },
            ("APPRO", _) if args.len() >= 2 => {
                let (Some(t), Ok(d)) = (self.target(args[0]), args[1].parse::<f64>()) else {
                    return self.refuse(35);
                };
                let straight = args.get(2) == Some(&"S");
                let c = self
                    .arm
                    .appro(t, [-d * mm, 0.0, 0.0, 0.0, 0.0, 0.0], straight, now);
                self.motion_answer(c, now)
            }
            ("DEPART", _) if !args.is_empty() => {
                let Ok(d) = args[0].parse::<f64>() else {
                    return self.refuse(12);
                };
                let straight = args.get(1) == Some(&"S");
                let c = self
                    .arm
                    .depart([-d * mm, 0.0, 0.0, 0.0, 0.0, 0.0], straight, now);
                self.motion_answer(c, now)
            }
            ("JOINT", Some([j, deg])) if j.fract() == 0.0 && (1.0..=6.0).contains(j) => {
                let c = self.arm.joint(*j as u8, deg.to_radians(), now);
                self.motion_answer(c, now)
            }
            ("MA" | "MI", Some(q)) if q.len() == 6 => {
                let f = match self.joint_units {
                    JointUnits::Degrees => 1f64.to_radians(),
                    JointUnits::Radians => 1.0,
                };
                let v: [f64; 6] = std::array::from_fn(|i| q[i] * f);
                let c = if word == "MA" {
                    self.arm.ma(v, now)
                } else {
                    self.arm.mi(v, now)
                };
                self.motion_answer(c, now)
            }
            ("JOG", Some([x, y, z])) => {
                let mut d = [x * mm, y * mm, z * mm];
                if self.profile.twin.jog_tool {
                    // Along the tool's axes where the arm will be: the controller's tool
                    // frame is TROL's turned by the profile's tool_rotation.
                    let q = self.arm.planned_end();
                    let p = self.arm.kinematics().fk(&q);
                    let [ty, tp, tr] = self.profile.tool_rotation.map(f64::to_radians);
                    let off = trol_a465::kinematics::Pose::from_xyzypr([0.0, 0.0, 0.0, ty, tp, tr]);
                    let r = p.rot * off.rot;
                    let v = r.x_axis * d[0] + r.y_axis * d[1] + r.z_axis * d[2];
                    d = [v.x, v.y, v.z];
                }
                let c = self.arm.jog(d, true, now);
                self.motion_answer(c, now)
            }
            ("HALT" | "ABORT", _) => {
                let stops = if word == "HALT" {
                    self.profile.twin.halt_stops
                } else {
                    self.profile.twin.abort_stops
                };
                if stops {
                    if self.arm.is_moving(now) {
                        self.stopped_short = true;
                    }
                    self.arm.halt(now);
                }
                self.ok("")
            }
            ("FINISH", _) => match self.profile.twin.finish {
                TwinFinish::Refused => self.refuse(12),
                TwinFinish::Waits if self.arm.is_moving(now) => {
                    self.waiting = Some(Waiting::FinishCommand);
                }
                _ => match self.profile.twin.finish_stopped {
                    n if n > 0 && self.stopped_short => self.refuse(n),
                    _ => self.ok(""),
                },
            },
            ("GRIP", Some([d])) => {
                let c = self.arm.grip(d * mm, now);
                self.answer(c)
            }
            ("OPEN", Some(f)) if f.len() <= 1 => {
                let c = self.arm.open(f.first().copied().unwrap_or(50.0), now);
                self.answer(c)
            }
            ("CLOSE", Some(f)) if f.len() <= 1 => {
                let c = self.arm.close(f.first().copied().unwrap_or(50.0), now);
                self.answer(c)
            }
            ("POINT", _) if args.len() == 7 => {
                let name = args[0].to_string();
                let vals: Option<Vec<f64>> = args[1..]
                    .iter()
                    .map(|a| a.parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect();
                let Some(v) = vals else {
                    return self.refuse(12);
                };
                let v: [f64; 6] = std::array::from_fn(|i| v[i]);
                let stored = if name.starts_with('#') {
                    if v.iter().any(|p| p.fract() != 0.0 || p.abs() > 1e9) {
                        return self.refuse(12);
                    }
                    Stored::Prec(v.map(|p| p as i32))
                    // (this controller's pulses; MOVE converts them)
                } else {
                    match self.frames.from_rapl(v) {
                        Ok(t) => Stored::Cart(t),
                        Err(_) => return self.refuse(12),
                    }
                };
                self.locations.insert(name, stored);
                self.ok("")
            }
            ("TOOL", _) if args.len() == 1 => match self.locations.get(args[0]) {
                Some(Stored::Cart(v)) => {
                    let v = *v;
                    let c = self.arm.set_tool(v);
                    self.answer(c)
                }
                _ => self.refuse(35),
            },
            ("HERE" | "ACTUAL", _) if args.len() == 1 => {
                let which = if word == "HERE" {
                    Which::Commanded
                } else {
                    Which::Actual
                };
                let q = self.arm.position(now, which);
                let stored = if args[0].starts_with('#') {
                    Stored::Prec(self.pulses_of(&q).map(|p| p as i32))
                } else {
                    Stored::Cart(self.arm.kinematics().fk_xyzypr(&q))
                };
                self.locations.insert(args[0].to_string(), stored);
                self.ok("")
            }
            ("SET", _) => match rest.split_once('=') {
                Some((to, from)) => match self.locations.get(from.trim()).copied() {
                    Some(l) => {
                        self.locations.insert(to.trim().to_string(), l);
                        self.ok("")
                    }
                    None => self.refuse(35),
                },
                None => self.refuse(12),
            },
            ("DLOC" | "DLOCN", _) if !args.is_empty() => {
                for a in &args {
                    self.locations.remove(*a);
                }
                self.ok("")
            }
            ("LISTL" | "LLOC", _) => {
                let rows: Vec<(String, Listed)> = self
                    .locations
                    .iter()
                    .filter(|(n, _)| args.is_empty() || args.contains(&n.as_str()))
                    .map(|(n, l)| {
                        let listed = match l {
                            Stored::Cart(v) => {
                                Listed::Cart(self.frames.to_rapl(*v).unwrap_or([0.0; 6]))
                            }
                            Stored::Prec(p) => Listed::Prec(p.map(i64::from)),
                            Stored::Joints(q) => Listed::Prec(self.pulses_of(q)),
                        };
                        (n.clone(), listed)
                    })
                    .collect();
                if rows.is_empty() && !args.is_empty() {
                    return self.refuse(35);
                }
                let body = text::write_listl(&rows);
                self.ok(&body)
            }
            ("W0" | "W2", _) => {
                let which = if word == "W0" {
                    Which::Commanded
                } else {
                    Which::Actual
                };
                let p = self.position(now, which);
                let body = text::write_position(word == "W0", &p);
                self.ok(&body)
            }
            ("W5", _) => {
                let dt = 0.01;
                let a = self.arm.position((now - dt).max(0.0), Which::Commanded);
                let b = self.arm.position(now, Which::Commanded);
                let v: [f64; 6] = std::array::from_fn(|i| {
                    if self.arm.is_moving(now) {
                        ((b[i] - a[i]) / dt).to_degrees()
                    } else {
                        0.0
                    }
                });
                let body = text::write_velocity(&v);
                self.ok(&body)
            }
            ("STATUS", _) => {
                let lagging = now - self.acked_at < self.profile.twin.done_lag_ms as f64 / 1000.0;
                let moving = self.arm.is_moving(now) && !lagging;
                let s = Status {
                    version: "RAPL-II Version 2.60     A465 Robot (simulated)".into(),
                    last_error: self.last_error.clone(),
                    speed: self.arm.speed(),
                    lock: [false; 6],
                    done: [!moving; 6],
                    limp: [self.limp; 6],
                    homed: self.arm.homed(),
                    metric: match self.profile.units {
                        crate::profile::Units::Inch => Some(false),
                        _ => Some(true),
                    },
                };
                let tool = self.frames.to_rapl(self.arm.kinematics().tool());
                let body = text::write_status(&s, &tool.unwrap_or([0.0; 6]));
                self.ok(&body)
            }
            ("SERIAL", _) => {
                let body = format!(
                    "\n\r\nDEVICE 0: {} BAUD, NO PARITY, 8 DATA, 1 STOP, {}\r\n",
                    self.profile.baud,
                    if self.profile.flow == crate::profile::Flow::Xonxoff {
                        "XON/XOFF"
                    } else {
                        "NO HANDSHAKE"
                    }
                );
                self.ok(&body)
            }
            ("LIMP", _) => {
                self.limp = true;
                self.arm.halt(now);
                self.ok("")
            }
            ("NOLIMP" | "ENABLE", _) | ("ARM", _) if !rest.contains("OFF") => {
                self.limp = false;
                self.ok("")
            }
            ("DELAY", Some([_])) => self.ok(""),
            // The probe's unknown word: refused as any, with the simulator's name in the text,
            // so that a session with a simulator's profile knows it talks to the simulator.
            (crate::probe::PROBE_WORD, _) if self.profile.twin.names_itself => {
                let line = self.refusal.write(12, SIMULATOR_SAYS);
                self.out.extend(b"\n");
                self.out.extend(line.bytes());
                self.last_error = line;
                self.prompt();
            }
            _ => self.refuse(12),
        }
    }
}
