//! A precision point's joints (docs/c500c.md, "Locations"): a `ploc` holds pulses, and how they
//! relate to degrees on a C500C is the profile's `pulses-per-degree` and `pulses-at-zero` (an
//! open point, measured by `trol c500c step pulses`). TROL believes them only as far as the arm
//! has shown them: every `w2` it reads of the arm at rest is checked against them, one
//! disagreement refuses them for the session, and a joint's ratio is used only once the arm has
//! been seen agreeing with it a degree or more from that joint's zero.

use trol_a465::kinematics::Pose;

use super::cartesian::{CartCall, flange};
use super::teach::Ploc;
use super::*;
use crate::pulses::{self, Pulses};

impl C500cBackend {
    /// A `w2` reading of the arm at rest (with no motion of TROL's under way, or at a
    /// motion's end as Finish sees it arrive), against the profile's pulses.
    pub(super) fn note_pulses(&mut self, p: &reports::Position) {
        let Some(rel) = self.profile.pulses() else {
            return;
        };
        let agrees = rel.agrees(&p.joints_deg, &p.pulses);
        for (j, agrees) in agrees.into_iter().enumerate() {
            if !agrees {
                if self.pulses_wrong.is_none() {
                    self.pulses_wrong = Some(format!(
                        "`w2` read joint {} at {:.3} degrees and {} pulses, where the profile \
                         gives {} pulses",
                        j + 1,
                        p.joints_deg[j],
                        p.pulses[j],
                        rel.pulses(&p.joints_deg)[j]
                    ));
                }
            } else if p.joints_deg[j].abs() >= pulses::TESTS_RATIO_DEG {
                self.pulses_seen[j] = true;
            }
        }
    }

    /// The profile's pulses, where the arm has not contradicted them (unset: refused, naming
    /// the keys and the step).
    pub(super) fn pulses_keys(&mut self) -> Result<Pulses, BackendError> {
        let Some(rel) = self.profile.pulses() else {
            self.unsettled(
                "a precision point's joints need the A465's pulses per degree on this C500C: \
                 set `pulses-per-degree` and `pulses-at-zero` in the C500C profile (`trol \
                 c500c step pulses` measures them on the arm)",
            )?;
            return Err(BackendError::Refused(UNSETTLED));
        };
        if let Some(why) = self.pulses_wrong.clone() {
            self.unsettled(&format!(
                "the profile's `pulses-per-degree` and `pulses-at-zero` are not this arm's \
                 ({why}): measure them again with `trol c500c step pulses`"
            ))?;
            return Err(BackendError::Refused(UNSETTLED));
        }
        Ok(rel)
    }

    /// A precision point's joints, degrees, where the profile's pulses have not been
    /// contradicted and every joint that needs its ratio has been seen agreeing with it.
    pub(super) fn ploc_degrees(&self, p: &[i64; 6]) -> Option<[f64; 6]> {
        let rel = self.profile.pulses()?;
        if self.pulses_wrong.is_some() || self.unseen_joint(&rel, p).is_some() {
            return None;
        }
        Some(rel.degrees(p))
    }

    /// The first joint (0-based) of the precision point `p` that stands off its zero with
    /// its ratio not yet seen on the arm.
    fn unseen_joint(&self, rel: &Pulses, p: &[i64; 6]) -> Option<usize> {
        (0..6).find(|&j| {
            !self.pulses_seen[j] && ((p[j] - rel.at_zero[j]) as f64).abs() > pulses::tolerance(0.0)
        })
    }

    /// An approach to the precision point `name` (its pulses read back with `print`): its
    /// joints by the profile's pulses, checked against `w2` where the arm stands, then the
    /// approach planned and sent as any cartesian one ([`Self::resolve_cart`]).
    pub(super) fn resolve_ploc_appro(
        &mut self,
        name: LocName,
        disp: [f64; 6],
        straight: bool,
    ) -> Result<Motion, BackendError> {
        let var = teach::ash_var(&name).ok_or(BackendError::UnknownLocation(name))?;
        self.taught_in("ploc", &var, name)?;
        let p = match self.print_ploc(&var)? {
            Ploc::At(p) => p,
            other => return Err(self.misread("ploc", &var, &other)),
        };
        // Where the arm stands, against the profile, before its values are used.
        let here = self.read_position(true)?;
        self.rests_at(here.joints_deg);
        let rel = self.pulses_keys()?;
        if let Some(j) = self.unseen_joint(&rel, &p) {
            self.unsettled(&format!(
                "{var} stands joint {n} away from its zero, and TROL has not yet seen the arm \
                 agree with the profile's pulses per degree of that joint in this session: \
                 move joint {n} by a degree or more first (TROLJoint), then try again",
                n = j + 1
            ))?;
            return Err(BackendError::Refused(UNSETTLED));
        }
        let deg = rel.degrees(&p);
        let tcp = flange(&deg).then(&Pose::from_xyzypr(self.tool)).to_xyzypr();
        self.resolve_cart(CartCall::Appro(tcp, disp), straight)
    }
}
