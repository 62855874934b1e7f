//! TCP lines between two ends in this process: where a listening line binds, and a second
//! client told at once that the line is busy while the first carries on.

use std::time::{Duration, Instant};

use trol_port::Port;
use trol_port::tcp::TcpLine;

fn soon() -> Instant {
    Instant::now() + Duration::from_secs(2)
}

#[test]
fn listen_with_a_bare_port_binds_this_machine_only() {
    for name in ["0", ":0"] {
        let line = TcpLine::listen(name, Duration::from_secs(1)).unwrap();
        let addr = line.local_addr().unwrap();
        assert!(addr.ip().is_loopback(), "{name}: {addr}");
        assert!(
            line.name().starts_with("listen://127.0.0.1:"),
            "{}",
            line.name()
        );
    }
}

#[test]
fn a_second_client_is_told_the_line_is_busy_and_the_first_carries_on() {
    let mut server = TcpLine::listen("127.0.0.1:0", Duration::from_secs(1)).unwrap();
    let addr = server.local_addr().unwrap().to_string();
    let mut first = trol_port::open(&format!("socket://{addr}"), &Default::default()).unwrap();
    first.send(b"one").unwrap();
    let mut buf = [0u8; 64];
    let n = server.recv(&mut buf, soon()).unwrap();
    assert_eq!(&buf[..n], b"one");

    let mut second = trol_port::open(&format!("socket://{addr}"), &Default::default()).unwrap();
    // The server turns it away on its next send or receive.
    server.send(b"two").unwrap();
    let err = second.recv(&mut buf, soon()).unwrap_err();
    assert!(err.to_string().contains("busy"), "{err}");
    // It stays closed until it is opened again.
    assert!(second.send(b"x").is_err());

    let n = first.recv(&mut buf, soon()).unwrap();
    assert_eq!(&buf[..n], b"two");
}
