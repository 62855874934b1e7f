//! Command codes and transaction classes (manual, "Kommandocodes und Transaktionsklassen").
//!
//! A command's class follows from its code: CAT1 from 0, CAT2 from 64, CAT3 from 128, CAT4
//! from 192. Within a class the codes have no gaps, and `LAST_CATx_CODE` is the largest one,
//! so a class's dispatch table on the controller has `LAST_CATx_CODE - base + 1` entries.
//! CAT2 has no commands yet (manual, "API der Transaktionsklasse CAT2"); its LAST code is one
//! below its base, an empty table.

/// A transaction class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// Commands that become one RAPL-BIOS call; the reply is one 16-bit integer.
    Cat1,
    /// Like CAT1, with replies of any length.
    Cat2,
    /// Commands the BIOS does not offer directly (here: GetPosition).
    Cat3,
    /// TROL's own commands (TerminatePCP, GetStatus).
    Cat4,
}

impl Class {
    /// The class of a command code.
    pub fn of(code: u8) -> Class {
        match code >> 6 {
            0 => Class::Cat1,
            1 => Class::Cat2,
            2 => Class::Cat3,
            _ => Class::Cat4,
        }
    }

    /// The first code of the class.
    pub fn base(self) -> u8 {
        self.index() as u8 * 64
    }

    /// 0 for CAT1 .. 3 for CAT4 (the dispatch table's number).
    pub fn index(self) -> usize {
        match self {
            Class::Cat1 => 0,
            Class::Cat2 => 1,
            Class::Cat3 => 2,
            Class::Cat4 => 3,
        }
    }

    /// The largest built-in code of the class (`LAST_CATx_CODE`).
    pub fn last_code(self) -> u8 {
        match self {
            Class::Cat1 => LAST_CAT1_CODE,
            Class::Cat2 => LAST_CAT2_CODE,
            Class::Cat3 => LAST_CAT3_CODE,
            Class::Cat4 => LAST_CAT4_CODE,
        }
    }

    /// All four, in order.
    pub const ALL: [Class; 4] = [Class::Cat1, Class::Cat2, Class::Cat3, Class::Cat4];
}

impl std::fmt::Display for Class {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "CAT{}", self.index() + 1)
    }
}

macro_rules! commands {
    ($( $(#[$doc:meta])* $variant:ident = $code:literal, $konst:ident, $name:literal; )*) => {
        /// The built-in commands, by code.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum Command {
            $( $(#[$doc])* $variant = $code, )*
        }

        $( #[doc = concat!("Command code of ", $name, ".")] pub const $konst: u8 = $code; )*

        impl Command {
            /// Every built-in command, in code order.
            pub const ALL: &'static [Command] = &[$(Command::$variant),*];

            /// The command with this code, if it is a built-in one.
            pub fn from_code(code: u8) -> Option<Command> {
                match code {
                    $( $code => Some(Command::$variant), )*
                    _ => None,
                }
            }

            /// The API function's name, as in the manual (`TROLMove`).
            pub fn api_name(self) -> &'static str {
                match self {
                    $( Command::$variant => $name, )*
                }
            }
        }
    };
}

commands! {
    /// TROLAppro: approach a named location, displaced in the tool frame.
    Appro = 0, TROL_APPRO, "TROLAppro";
    /// TROLApproII: approach a given location.
    ApproII = 1, TROL_APPRO_II, "TROLApproII";
    /// TROLClose: close the gripper with a force.
    Close = 2, TROL_CLOSE, "TROLClose";
    /// TROLDepart: move away from here in the tool frame.
    Depart = 3, TROL_DEPART, "TROLDepart";
    /// TROLFinish: ask whether, or wait until, motion has ended.
    Finish = 4, TROL_FINISH, "TROLFinish";
    /// TROLGrip: set the finger distance.
    Grip = 5, TROL_GRIP, "TROLGrip";
    /// TROLHalt: stop all motion.
    Halt = 6, TROL_HALT, "TROLHalt";
    /// TROLHome: home one axis or all.
    Home = 7, TROL_HOME, "TROLHome";
    /// TROLJog: move the tool in the world frame.
    Jog = 8, TROL_JOG, "TROLJog";
    /// TROLJoint: move one joint by an increment.
    Joint = 9, TROL_JOINT, "TROLJoint";
    /// TROLMA: move all joints to absolute angles.
    Ma = 10, TROL_MA, "TROLMA";
    /// TROLMI: move all joints by increments.
    Mi = 11, TROL_MI, "TROLMI";
    /// TROLMove: move to a named location.
    Move = 12, TROL_MOVE, "TROLMove";
    /// TROLMoveII: move to a given location.
    MoveII = 13, TROL_MOVE_II, "TROLMoveII";
    /// TROLOpen: open the gripper with a force.
    Open = 14, TROL_OPEN, "TROLOpen";
    /// TROLReady: go to the READY pose.
    Ready = 15, TROL_READY, "TROLReady";
    /// TROLSetToolTransform: set the tool transform.
    SetToolTransform = 16, TROL_SET_TOOL_TRANSFORM, "TROLSetToolTransform";
    /// TROLSpeed: set the speed of the following motions.
    Speed = 17, TROL_SPEED, "TROLSpeed";
    /// TROLGetPosition: read the position (CAT3).
    GetPosition = 128, TROL_GET_POSITION, "TROLGetPosition";
    /// TROLTerminatePCP: end server mode (CAT4).
    TerminatePcp = 192, TROL_TERMINATE_PCP, "TROLTerminatePCP";
    /// TROLGetStatus: whether the last CAT1/CAT2 command called the BIOS, and its result (CAT4).
    GetStatus = 193, TROL_GET_STATUS, "TROLGetStatus";
}

/// The largest CAT1 code.
pub const LAST_CAT1_CODE: u8 = TROL_SPEED;
/// The largest CAT2 code: CAT2 has no commands, so this is one below its base (63).
pub const LAST_CAT2_CODE: u8 = 63;
/// The largest CAT3 code.
pub const LAST_CAT3_CODE: u8 = TROL_GET_POSITION;
/// The largest CAT4 code.
pub const LAST_CAT4_CODE: u8 = TROL_GET_STATUS;

impl Command {
    /// The command code (the first byte of its request).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// Its transaction class.
    pub fn class(self) -> Class {
        Class::of(self.code())
    }

    /// The name without the TROL prefix (`Move`).
    pub fn short_name(self) -> &'static str {
        &self.api_name()[4..]
    }

    /// The command with this name, case-insensitive, with or without the TROL prefix.
    pub fn from_name(name: &str) -> Option<Command> {
        let lower = name.to_ascii_lowercase();
        let bare = lower.strip_prefix("trol").unwrap_or(&lower);
        Command::ALL
            .iter()
            .copied()
            .find(|c| c.short_name().eq_ignore_ascii_case(bare))
    }
}

impl std::fmt::Display for Command {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.api_name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_lie_in_their_class_without_gaps() {
        for class in Class::ALL {
            let codes: Vec<u8> = Command::ALL
                .iter()
                .filter(|c| c.class() == class)
                .map(|c| c.code())
                .collect();
            let expected: Vec<u8> = (class.base()..=class.last_code()).collect();
            assert_eq!(codes, expected, "{class}");
        }
        assert_eq!(LAST_CAT1_CODE, 17);
        assert_eq!(Class::of(LAST_CAT4_CODE), Class::Cat4);
    }

    #[test]
    fn names_round_trip() {
        for &c in Command::ALL {
            assert_eq!(Command::from_code(c.code()), Some(c));
            assert_eq!(Command::from_name(c.api_name()), Some(c));
            assert_eq!(Command::from_name(&c.short_name().to_uppercase()), Some(c));
        }
        assert_eq!(Command::from_name("trolmoveii"), Some(Command::MoveII));
        assert_eq!(Command::from_name("fly"), None);
    }
}
