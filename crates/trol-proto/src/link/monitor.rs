//! A passive reader of one direction of a line (what `trol trace` shows): bytes in, what
//! they are out. Control codes, headers and frames with the block check each passes, whole
//! messages with their PCI, and the text of a terminal outside the protocol. It sends
//! nothing and keeps no time: it reads a line it is not part of, so it takes either block
//! check (the activation line agrees on one, and a capture may start after it) and a
//! damaged byte as what it is within one bit of, as a receiver does.

use super::BlockCheck;
use super::control::{ACK, ENQ, EOT, ETB, ETX, NAK, SOH, STX, SYN, accepts};
use super::frame::{self, FRAME_SIZE, HEADER_LEN, frame_count};

/// What a frame ends with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameEnd {
    /// ETX: the message's last frame.
    Etx,
    /// ETB: more frames follow.
    Etb,
    /// Neither.
    Bad,
}

/// A message whose last frame went by and whose EOT closed it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Message {
    /// Whole, and (in CRC-16 mode) its message check matches: what the receiver delivers.
    Delivered {
        /// The header's PCI.
        pci: u16,
        /// The message.
        bytes: Vec<u8>,
    },
    /// Frames missing: `got` of `len` bytes.
    Incomplete {
        /// Bytes received in good frames.
        got: usize,
        /// The header's length.
        len: usize,
    },
    /// All frames, but the message check in the PCI does not match (CRC-16 mode): the
    /// receiver does not deliver it.
    CheckWrong,
}

/// One thing seen on the line.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Seen {
    /// A line of terminal text (bytes outside the protocol, up to CR or LF or a block).
    Text(Vec<u8>),
    /// ENQ, ACK, EOT or the controller's keep-alive SYN (the byte as it is defined).
    Control(u8),
    /// A NAK and its code byte.
    Nak(u8),
    /// A byte outside a block, or a control code out of place.
    Stray(u8),
    /// A header block.
    Header {
        /// The message's length.
        len: usize,
        /// The PCI as sent (in CRC-16 mode its bits 9..15 are the message's check).
        pci: u16,
        /// The message's first word, carried in the header.
        first_word: [u8; 2],
        /// The block check character.
        bcc: u16,
        /// The block check it passes, if any.
        check: Option<BlockCheck>,
    },
    /// A frame.
    Frame {
        /// Its index (recovered from the field, which in CRC-16 mode carries a check too).
        index: u16,
        /// Its data.
        data: Vec<u8>,
        /// The block check character.
        bcc: u16,
        /// The block check it passes, if any.
        check: Option<BlockCheck>,
        /// What it ends with.
        end: FrameEnd,
    },
    /// The EOT after a message: the message as the receiver takes it.
    Message(Message),
}

/// The message being read: its length, PCI, bytes so far, frames accepted, and the block
/// check its header passed.
#[derive(Debug)]
struct Partial {
    len: usize,
    pci: u16,
    bytes: Vec<u8>,
    frames: usize,
    check: Option<BlockCheck>,
}

/// One direction's reader.
#[derive(Debug, Default)]
pub struct Monitor {
    pending: Vec<u8>,
    message: Option<Partial>,
    text: Vec<u8>,
    /// An ENQ went by from this side: a header may follow, so a byte within one bit of SOH
    /// starts one (otherwise only SOH itself does: `>` of a prompt is one bit away).
    after_enq: bool,
}

/// Which block check a BCC matches, if any.
pub fn check_of(bcc: u16, of: impl Fn(BlockCheck) -> u16) -> Option<BlockCheck> {
    [BlockCheck::Crc16, BlockCheck::Lrc]
        .into_iter()
        .find(|c| of(*c) == bcc)
}

impl Monitor {
    /// A reader with nothing seen.
    pub fn new() -> Monitor {
        Monitor::default()
    }

    /// Bytes from this direction; what they complete, in order.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Seen> {
        let mut seen = Vec::new();
        self.pending.extend_from_slice(bytes);
        while let Some(&b) = self.pending.first() {
            // Inside a message a block starts with SOH or STX, and its length is known.
            let need = if b == SOH || (self.after_enq && accepts(b, SOH)) {
                HEADER_LEN
            } else if accepts(b, STX) {
                match &self.message {
                    Some(m) if m.frames < frame_count(m.len) => {
                        let start = 2 + m.frames * FRAME_SIZE;
                        (m.len - start).min(FRAME_SIZE) + 6
                    }
                    _ => 1,
                }
            } else if accepts(b, NAK) && !(b.is_ascii_graphic() || b == b' ') {
                // (`R` is one bit from NAK: printable bytes outside a block are text.)
                2
            } else {
                1
            };
            if self.pending.len() < need {
                break;
            }
            let block: Vec<u8> = self.pending.drain(..need).collect();
            self.block(&block, &mut seen);
        }
        seen
    }

    /// Terminal text not yet ended by CR or LF (at the end of a capture).
    pub fn flush_text(&mut self) -> Option<Seen> {
        (!self.text.is_empty()).then(|| Seen::Text(std::mem::take(&mut self.text)))
    }

    fn block(&mut self, block: &[u8], seen: &mut Vec<Seen>) {
        let b = block[0];
        if block.len() == 1 && (b.is_ascii_graphic() || b == b' ' || b == b'\r' || b == b'\n') {
            self.text.push(b);
            if b == b'\r' || b == b'\n' {
                seen.extend(self.flush_text());
            }
            return;
        }
        seen.extend(self.flush_text());
        if block.len() == HEADER_LEN && accepts(b, SOH) {
            self.after_enq = false;
            let mut header = [0u8; HEADER_LEN];
            header.copy_from_slice(block);
            let frame::Header {
                len,
                pci,
                first_word,
            } = frame::Header::decode_fields(&header);
            let len = usize::from(len);
            let bcc = u16::from_le_bytes([block[7], block[8]]);
            let check = check_of(bcc, |c| frame::bcc(c, &block[1..7]));
            let ok = check.is_some() && accepts(block[9], ETX);
            self.message = ok.then(|| Partial {
                len,
                pci,
                bytes: first_word[..len.min(2)].to_vec(),
                frames: 0,
                check,
            });
            seen.push(Seen::Header {
                len,
                pci,
                first_word,
                bcc,
                check,
            });
            return;
        }
        if accepts(b, STX) && block.len() > 6 {
            let n = block.len() - 6;
            let data = &block[1..1 + n];
            let field = [block[1 + n], block[2 + n]];
            let bcc = u16::from_le_bytes([block[3 + n], block[4 + n]]);
            let check = check_of(bcc, |c| frame::frame_bcc(c, data, field));
            // In CRC-16 mode the field is the index XOR a second CRC of the data.
            let index = frame::frame_index_of(
                check.unwrap_or(BlockCheck::Lrc),
                u16::from_le_bytes(field),
                data,
            );
            let end = match block[5 + n] {
                e if accepts(e, ETX) => FrameEnd::Etx,
                e if accepts(e, ETB) => FrameEnd::Etb,
                _ => FrameEnd::Bad,
            };
            if let Some(m) = self.message.as_mut()
                && check.is_some()
                && usize::from(index) == m.frames
            {
                m.bytes.extend_from_slice(data);
                m.frames += 1;
            }
            seen.push(Seen::Frame {
                index,
                data: data.to_vec(),
                bcc,
                check,
                end,
            });
            return;
        }
        if accepts(b, NAK) && block.len() == 2 {
            seen.push(Seen::Nak(block[1]));
            return;
        }
        let control = [ENQ, ACK, EOT, SYN].into_iter().find(|c| accepts(b, *c));
        let Some(control) = control else {
            seen.push(Seen::Stray(b));
            return;
        };
        seen.push(Seen::Control(control));
        self.after_enq = control == ENQ;
        if control == EOT
            && let Some(m) = self.message.take()
        {
            seen.push(Seen::Message(if m.bytes.len() != m.len {
                Message::Incomplete {
                    got: m.bytes.len(),
                    len: m.len,
                }
            } else if m.check == Some(BlockCheck::Crc16)
                && frame::line_pci(BlockCheck::Crc16, m.pci, &m.bytes) != m.pci
            {
                Message::CheckWrong
            } else {
                Message::Delivered {
                    pci: m.pci,
                    bytes: m.bytes,
                }
            }));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::LinkConfig;

    /// A message sent by the link's own sender, read back by the monitor: header, frames,
    /// EOT, and the message delivered whole, in either block check.
    #[test]
    fn a_sent_message_is_read_back_whole() {
        for check in [BlockCheck::Lrc, BlockCheck::Crc16] {
            let cfg = LinkConfig {
                check,
                ..LinkConfig::default()
            };
            let message: Vec<u8> = (0..300u16).map(|i| i as u8).collect();
            let pci = frame::line_pci(check, 0x0105, &message);
            let mut wire = vec![ENQ];
            wire.extend(frame::Header::for_message(&message, pci).encode(cfg.check));
            for i in 0..frame_count(message.len()) {
                frame::encode_frame(&message, i, check, &mut wire);
            }
            wire.push(EOT);
            let mut m = Monitor::new();
            // Byte by byte: blocks are found whatever the chunks.
            let seen: Vec<Seen> = wire.iter().flat_map(|b| m.feed(&[*b])).collect();
            assert_eq!(seen[0], Seen::Control(ENQ));
            assert!(
                matches!(seen[1], Seen::Header { len: 300, check: Some(c), .. } if c == check),
                "{:?}",
                seen[1]
            );
            let frames = seen
                .iter()
                .filter(|s| matches!(s, Seen::Frame { check: Some(_), .. }))
                .count();
            assert_eq!(frames, frame_count(300));
            assert_eq!(
                seen.last(),
                Some(&Seen::Message(Message::Delivered {
                    pci,
                    bytes: message.clone()
                }))
            );
        }
    }

    #[test]
    fn text_naks_and_stray_bytes() {
        let mut m = Monitor::new();
        let seen = m.feed(b">>PCP TROL\r");
        assert_eq!(seen, vec![Seen::Text(b">>PCP TROL\r".to_vec())]);
        let seen = m.feed(&[NAK, 0x03, 0x00]);
        assert_eq!(seen, vec![Seen::Nak(0x03), Seen::Stray(0x00)]);
        assert_eq!(m.feed(b"abc"), vec![]);
        assert_eq!(m.flush_text(), Some(Seen::Text(b"abc".to_vec())));
    }
}
