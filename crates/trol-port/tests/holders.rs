//! Who holds a pseudo-terminal (`trol_port::holders`, the "in use by process N" of a busy
//! port): the process that made the pty (it has that pty's master open) is the line's other
//! end and is left out; a process that has the line end open and the masters of *other*
//! ptys only (a test program with several lines, a relay) is a rival and is named. Before,
//! any master open made a process "the maker", so a busy port went unnamed whenever its
//! holder had another line of its own (found with eight test threads at once).

#![cfg(target_os = "linux")]

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};

/// A Python child that runs `code` and prints one line when it is ready; killed on drop.
struct Helper {
    child: Child,
    said: String,
}

impl Helper {
    fn start(code: &str, args: &[&str]) -> Helper {
        let mut child = Command::new("python3")
            .arg("-c")
            .arg(code)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .expect("python3 runs");
        let mut said = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut said)
            .unwrap();
        Helper {
            child,
            said: said.trim().to_string(),
        }
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

const MAKER: &str = "import os, pty, sys, time\n\
m, s = pty.openpty()\n\
print(os.ttyname(s), flush=True)\n\
time.sleep(60)\n";

const RIVAL: &str = "import os, pty, sys, time\n\
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)\n\
m, s = pty.openpty()\n\
print('ready', flush=True)\n\
time.sleep(60)\n";

#[test]
fn the_maker_of_this_pty_is_left_out_and_a_holder_with_other_ptys_is_named() {
    let maker = Helper::start(MAKER, &[]);
    let line = maker.said.clone();
    assert!(line.starts_with("/dev/pts/"), "{line}");
    let maker_pid = maker.child.id();
    assert!(
        !trol_port::holders(&line).iter().any(|h| h.pid == maker_pid),
        "the maker is the other end, not a rival"
    );
    let rival = Helper::start(RIVAL, &[&line]);
    assert_eq!(rival.said, "ready");
    let found = trol_port::holders(&line);
    assert!(
        found.iter().any(|h| h.pid == rival.child.id()),
        "the rival holds the line end (and a pty of its own): {found:?}"
    );
    assert!(!found.iter().any(|h| h.pid == maker_pid), "{found:?}");
}
