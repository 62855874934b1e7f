//! What the TROL utilities share: the `trol` binary (src/main.rs) and `trol-bench`
//! (crates/trol-bench). Where the controller is (trol.cfg and the flags that override it),
//! logging, output that never panics, and the progress display while the arm works.

/// `println!` that does not panic when nobody reads stdout any more (`trol demo | head -1`):
/// the line is dropped and [`common::stdout_closed`] says so from then on.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::common::say(format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics: a message to a standard error nobody reads any more (`trol
/// demo 2>&1 | head -3`) is dropped instead of ending the program with a panic.
#[macro_export]
macro_rules! tell {
    ($($arg:tt)*) => {
        $crate::common::tell(format_args!($($arg)*))
    };
}

pub mod common;
