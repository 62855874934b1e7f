//! Control codes of layer 2 (manual, "Protokoll der Schicht 2", section "Steuercodes").
//!
//! The manual asks that the codes differ pairwise in at least 3 bits, so that a received byte
//! that differs in at most 1 bit from the code expected at that point can be accepted as that
//! code. It does not print the values (they lived in `protoc.h`). We chose codewords of
//! the extended (8,4) Hamming code: every pair differs in exactly 4 bits, and each is 4 bits
//! away from 0x00 and 0xFF, the bytes a floating or broken line tends to produce. The ASCII
//! values of these names (SOH=0x01, ETX=0x03, ...) differ in a single bit and could not be used.

/// Start Of Header.
pub const SOH: u8 = 0x1E;
/// Start Of Text: starts a data frame.
pub const STX: u8 = 0x2D;
/// End Of Text: ends the header and the last frame.
pub const ETX: u8 = 0x4B;
/// End Of Transmission Block: ends every frame but the last.
pub const ETB: u8 = 0x78;
/// End Of Transmission: the sender closes the connection.
pub const EOT: u8 = 0x87;
/// Enquiry: the sender asks to open a connection.
pub const ENQ: u8 = 0x99;
/// Positive acknowledgement.
pub const ACK: u8 = 0xB4;
/// Negative acknowledgement; the next byte is a NAK code.
pub const NAK: u8 = 0xD2;
/// Synchronous idle (Decision, not in the manual): the controller's "still working", sent
/// while it executes a request, to a host of this protocol only, so that the host tells a
/// controller that works long from one that died (docs/protocol.md, "Keep-alive"). A ninth
/// codeword of the same code, 4 bits from each of the others.
pub const SYN: u8 = 0x66;

/// All control codes with their names, for documentation, tests and traces.
pub const ALL: [(&str, u8); 9] = [
    ("SOH", SOH),
    ("STX", STX),
    ("ETX", ETX),
    ("ETB", ETB),
    ("EOT", EOT),
    ("ENQ", ENQ),
    ("ACK", ACK),
    ("NAK", NAK),
    ("SYN", SYN),
];

/// Number of bits in which `a` and `b` differ.
pub const fn distance(a: u8, b: u8) -> u32 {
    (a ^ b).count_ones()
}

/// Whether `received` is accepted as the control code `expected`: it may differ in at most
/// one bit (manual: "in weniger als 2 Bits").
pub const fn accepts(received: u8, expected: u8) -> bool {
    distance(received, expected) <= 1
}

/// The name of a control code that `byte` would be accepted as, if any (for traces).
pub fn name_of(byte: u8) -> Option<&'static str> {
    ALL.iter().find(|(_, c)| accepts(byte, *c)).map(|(n, _)| *n)
}
