//! The commands one side knows: the built-in ones and those an application added
//! (manual, "Erweiterung von TROL um eigene Kommandos").
//!
//! Whoever reads or writes records by code (the controller's server, the trace, the
//! interpreter, the logs) looks the command up here, so an added command is decoded, checked
//! and shown by the name and arguments it was described with.

use super::code::CodeTable;
use super::command::CommandDef;
use super::record::{self, RequestError, Value};
use super::reply::Reply;
use super::table::BUILTIN;

/// A set of command descriptions, one per code and per name.
#[derive(Clone, Debug)]
pub struct Catalog {
    defs: Vec<CommandDef>,
}

/// Why a description could not be added.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CatalogError {
    /// Another command has the code.
    CodeTaken {
        /// The code.
        code: u8,
        /// The command that has it.
        by: &'static str,
    },
    /// Another command has the name.
    NameTaken(&'static str),
}

impl std::fmt::Display for CatalogError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CatalogError::CodeTaken { code, by } => write!(f, "code {code} is {by}'s already"),
            CatalogError::NameTaken(n) => write!(f, "a command is named {n} already"),
        }
    }
}

impl std::error::Error for CatalogError {}

impl Default for Catalog {
    fn default() -> Self {
        Catalog::builtin()
    }
}

impl Catalog {
    /// The built-in commands.
    pub fn builtin() -> Catalog {
        Catalog {
            defs: BUILTIN.iter().map(|d| **d).collect(),
        }
    }

    /// Add a description; its code and name must be free.
    pub fn add(&mut self, def: CommandDef) -> Result<(), CatalogError> {
        if let Some(other) = self.get(def.code) {
            return Err(CatalogError::CodeTaken {
                code: def.code,
                by: other.name,
            });
        }
        if self.find(def.name).is_some() {
            return Err(CatalogError::NameTaken(def.name));
        }
        let at = self.defs.partition_point(|d| d.code < def.code);
        self.defs.insert(at, def);
        Ok(())
    }

    /// The command with this code.
    pub fn get(&self, code: u8) -> Option<&CommandDef> {
        self.defs.iter().find(|d| d.code == code)
    }

    /// The command with this name (any case, with or without the TROL prefix), or with one
    /// of its RAPL-II names (`listl`, `dlocn`, `point`: [`super::table::ALIASES`]).
    pub fn find(&self, name: &str) -> Option<&CommandDef> {
        self.defs.iter().find(|d| d.is_named(name)).or_else(|| {
            let code = super::table::ALIASES
                .iter()
                .find(|(alias, _)| alias.eq_ignore_ascii_case(name))?
                .1;
            self.get(code)
        })
    }

    /// Every command, in code order.
    pub fn iter(&self) -> impl Iterator<Item = &CommandDef> {
        self.defs.iter()
    }

    /// Decode a request: its command and arguments, or why not (with the manual's code).
    pub fn decode(&self, request: &[u8]) -> Result<(&CommandDef, Vec<Value>), RequestError> {
        let code = *request.first().ok_or(RequestError::Unknown(None))?;
        let def = self.get(code).ok_or(RequestError::Unknown(Some(code)))?;
        Ok((def, record::decode(def, request)?))
    }

    /// A request in words (`TROLHome 0`), or what is wrong with it.
    pub fn request_text(&self, request: &[u8]) -> String {
        match self.decode(request) {
            Ok((def, values)) => record::format_call(def, &values),
            Err(e) => format!(
                "undecodable request {:02x?}: {e}",
                &request[..request.len().min(16)]
            ),
        }
    }

    /// A reply to `request` in words, BIOS codes named from `bios`.
    pub fn reply_text(&self, request: &[u8], reply: &[u8], bios: &CodeTable) -> String {
        let Some(def) = request.first().and_then(|c| self.get(*c)) else {
            return format!("reply {reply:02x?}");
        };
        match Reply::decode(def, reply) {
            Ok(r) => r.text(bios),
            Err(e) => format!("reply {reply:02x?}: {e}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::command::{Arg, ArgKind, ReplyKind, Wait};

    const SPEEDS: CommandDef = CommandDef {
        code: 64,
        name: "TROLGetJointSpeeds",
        args: &[Arg {
            name: "axis",
            kind: ArgKind::Int { min: 0, max: 6 },
        }],
        reply: ReplyKind::Reals { min: 1, max: 6 },
        success: &[],
        wait: Wait::Reply,
        help: "joint speeds",
    };

    #[test]
    fn an_added_command_is_decoded_and_shown_by_its_description() {
        let mut c = Catalog::builtin();
        assert_eq!(
            c.request_text(&[64, 3]),
            "undecodable request [40, 03]: TROL_ERR_UNKNOWN: unknown command code 64"
        );
        c.add(SPEEDS).unwrap();
        assert_eq!(c.request_text(&[64, 3]), "TROLGetJointSpeeds 3");
        assert!(c.request_text(&[64, 9]).contains("TROL_ERR_ARG_RANGE"));
        let mut reply = vec![0, 0];
        reply.extend_from_slice(&1.5f32.to_le_bytes());
        assert_eq!(
            c.reply_text(&[64, 3], &reply, &[]),
            "0 (success), values (1.5)"
        );
        assert_eq!(c.find("getjointspeeds").unwrap().code, 64);
        assert_eq!(
            c.add(SPEEDS),
            Err(CatalogError::CodeTaken {
                code: 64,
                by: "TROLGetJointSpeeds"
            })
        );
        assert_eq!(
            c.add(CommandDef { code: 65, ..SPEEDS }),
            Err(CatalogError::NameTaken("TROLGetJointSpeeds"))
        );
    }
}
