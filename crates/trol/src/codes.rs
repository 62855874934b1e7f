//! The BIOS code tables controllers tell (TROLGetCodes), kept for the life of the process.
//!
//! A [`CodeTable`] names codes with `&'static str`s, so that every surface can hold one
//! without lifetimes. A table a controller told is made static once: the same table told
//! again (a reconnect, a second connection to the same kind of controller) is the one kept
//! before, so reconnecting never grows the memory.

use std::sync::Mutex;

use trol_proto::application::{CodeEntry, CodeInfo, CodeTable};

static TABLES: Mutex<Vec<&'static CodeTable>> = Mutex::new(Vec::new());

/// The static table with exactly `codes`, made once per distinct table.
pub fn intern(codes: &[CodeEntry]) -> &'static CodeTable {
    let same = |t: &CodeTable| {
        t.len() == codes.len()
            && t.iter()
                .zip(codes)
                .all(|(a, b)| a.value == b.value && a.name == b.name && a.meaning == b.meaning)
    };
    let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(t) = tables.iter().find(|t| same(t)) {
        return t;
    }
    let table: Vec<CodeInfo> = codes
        .iter()
        .map(|c| CodeInfo {
            value: c.value,
            name: Box::leak(c.name.clone().into_boxed_str()),
            meaning: Box::leak(c.meaning.clone().into_boxed_str()),
        })
        .collect();
    let table: &'static CodeTable = Box::leak(table.into_boxed_slice());
    tables.push(table);
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_table_is_kept_once() {
        let entry = |v: i16, n: &str| CodeEntry {
            value: v,
            name: n.into(),
            meaning: format!("{n} happened"),
        };
        let a = intern(&[entry(-1, "BIOS_A"), entry(-2, "BIOS_B")]);
        let b = intern(&[entry(-1, "BIOS_A"), entry(-2, "BIOS_B")]);
        assert!(std::ptr::eq(a, b));
        assert_eq!(a[1].name, "BIOS_B");
        assert_eq!(a[1].meaning, "BIOS_B happened");
        let c = intern(&[entry(-1, "BIOS_A")]);
        assert!(!std::ptr::eq(a, c));
        assert_eq!(c.len(), 1);
    }
}
