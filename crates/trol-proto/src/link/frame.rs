//! Byte layout of the header and the data frames (manual, "Protokoll der Schicht 2",
//! "Datenübertragung"). All 16-bit fields are little-endian.
//!
//! ```text
//! header: SOH | #bytes (2) | PCI (2) | firstWord (2) | BCC (2) | ETX          = 10 bytes
//! frame:  STX | data (1..FRAME_SIZE) | frame-ID (2) | BCC (2) | ETB or ETX   = 7..FRAME_SIZE+6
//! ```
//!
//! The BCC covers every byte of the block except the control codes (and except the BCC
//! itself): the manual's LRC (their sum modulo 2^16), or CRC-16/CCITT ([`BlockCheck`]). In
//! CRC-16 mode two fields carry more checks at no cost on the line: the frame-ID field is the
//! index XOR a second CRC of the frame's data ([`frame_id_field`]), and the PCI's bits 9..15
//! a check of the whole message ([`message_check`]).

use super::config::BlockCheck;
use super::control::{ETB, ETX, SOH, STX};

/// Largest number of data bytes in one frame. The manual defines FRAME_SIZE in `protoc.h`
/// without printing it; 256 gives a line efficiency above 96 % for a 64 KiB message while a
/// frame lost to noise costs only a quarter of a second at 9600 baud. See docs/protocol.md.
pub const FRAME_SIZE: usize = 256;

/// How often one block (header or frame) may be sent again after a retry NAK, by default.
/// The manual defines MAX_RETRIES in `protoc.h` without printing it.
pub const MAX_RETRIES: u8 = 5;

/// Length of the header in bytes.
pub const HEADER_LEN: usize = 10;

/// Bytes a frame adds to its data: STX, frame-ID (2), BCC (2), ETB/ETX.
pub const FRAME_OVERHEAD: usize = 6;

/// Largest message: #bytes is a 16-bit field.
pub const MAX_MESSAGE: usize = u16::MAX as usize;

/// The manual's LRC: the sum of the bytes, modulo 2^16.
pub fn lrc(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0u16, |acc, &b| acc.wrapping_add(u16::from(b)))
}

const CCITT: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

/// CRC-16/CCITT (polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR).
pub fn crc16(bytes: &[u8]) -> u16 {
    CCITT.checksum(bytes)
}

const ARC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_ARC);
const MMC7: crc::Crc<u8> = crc::Crc::<u8>::new(&crc::CRC_7_MMC);

/// In CRC-16 mode, the PCI bits that reach layer 3 (the transaction number and REPEAT);
/// bits 9..15 carry the message check on the line.
pub const PCI_LAYER3_BITS: u16 = 0x01FF;

/// CRC-16 mode's check of the whole message, 7 bits (CRC-7/MMC, polynomial 0x09) over
/// #bytes (little-endian), the PCI's layer-3 bits (little-endian) and every message byte.
/// It rides in the PCI's bits 9..15, so a header or frame whose own CRC-16 missed damage
/// is still caught before the message is delivered, at no cost on the line.
pub fn message_check(len: u16, pci: u16, message: &[u8]) -> u16 {
    let mut d = MMC7.digest();
    d.update(&len.to_le_bytes());
    d.update(&(pci & PCI_LAYER3_BITS).to_le_bytes());
    d.update(message);
    u16::from(d.finalize() & 0x7F)
}

/// The PCI as it goes on the line: in CRC-16 mode the layer-3 bits with the message check
/// in bits 9..15; with the LRC the PCI as layer 3 gave it (the manual's).
pub fn line_pci(check: BlockCheck, pci: u16, message: &[u8]) -> u16 {
    match check {
        BlockCheck::Lrc => pci,
        BlockCheck::Crc16 => {
            let own = pci & PCI_LAYER3_BITS;
            own | (message_check(message.len() as u16, own, message) << 9)
        }
    }
}

/// The frame-ID field of frame `index` carrying `data`: the index with the LRC (the
/// manual's), the index XOR a second CRC of the data (CRC-16/ARC, polynomial 0x8005) in
/// CRC-16 mode, so that a frame has 32 check bits at no cost on the line.
pub fn frame_id_field(check: BlockCheck, index: usize, data: &[u8]) -> u16 {
    match check {
        BlockCheck::Lrc => index as u16,
        BlockCheck::Crc16 => (index as u16) ^ ARC.checksum(data),
    }
}

/// The frame index a frame-ID field names, given the frame's data (the inverse of
/// [`frame_id_field`]).
pub fn frame_index_of(check: BlockCheck, field: u16, data: &[u8]) -> u16 {
    match check {
        BlockCheck::Lrc => field,
        BlockCheck::Crc16 => field ^ ARC.checksum(data),
    }
}

/// The BCC of a block's checked bytes (header: the six between SOH and BCC; frame: the data
/// and the frame-ID).
pub fn bcc(check: BlockCheck, bytes: &[u8]) -> u16 {
    match check {
        BlockCheck::Lrc => lrc(bytes),
        BlockCheck::Crc16 => crc16(bytes),
    }
}

/// Number of frames that follow the header for a message of `len` bytes (the manual's
/// `#frames` formula; the first two bytes travel in the header).
pub const fn frame_count(len: usize) -> usize {
    if len <= 2 {
        0
    } else {
        (len - 2).div_ceil(FRAME_SIZE)
    }
}

/// The range of message bytes that frame `index` carries.
pub fn frame_range(len: usize, index: usize) -> std::ops::Range<usize> {
    let start = 2 + index * FRAME_SIZE;
    start.min(len)..(start + FRAME_SIZE).min(len)
}

/// Length on the line of frame `index` of a message of `len` bytes.
pub fn frame_wire_len(len: usize, index: usize) -> usize {
    frame_range(len, index).len() + FRAME_OVERHEAD
}

/// Total bytes both ends put on the line for one error-free transfer of `len` bytes:
/// ENQ, ACK, header, ACK, every frame with its ACK, EOT.
pub fn wire_bytes_for(len: usize) -> usize {
    let frames = frame_count(len);
    let data_in_frames = len.saturating_sub(2);
    1 + 1 + HEADER_LEN + 1 + data_in_frames + frames * (FRAME_OVERHEAD + 1) + 1
}

/// The header's fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Number of bytes in the message (#bytes).
    pub len: u16,
    /// Protocol Control Information for layer 3.
    pub pci: u16,
    /// The first two message bytes; zero where the message is shorter.
    pub first_word: [u8; 2],
}

impl Header {
    /// The header of `message` with `pci`. `message` must hold at most 65535 bytes.
    pub fn for_message(message: &[u8], pci: u16) -> Header {
        debug_assert!(message.len() <= MAX_MESSAGE);
        let mut first_word = [0u8; 2];
        for (dst, src) in first_word.iter_mut().zip(message) {
            *dst = *src;
        }
        Header {
            len: message.len() as u16,
            pci,
            first_word,
        }
    }

    /// The six bytes between SOH and BCC.
    pub fn body(&self) -> [u8; 6] {
        let l = self.len.to_le_bytes();
        let p = self.pci.to_le_bytes();
        [
            l[0],
            l[1],
            p[0],
            p[1],
            self.first_word[0],
            self.first_word[1],
        ]
    }

    /// The header as it goes on the line.
    pub fn encode(&self, check: BlockCheck) -> [u8; HEADER_LEN] {
        let body = self.body();
        let bcc = bcc(check, &body).to_le_bytes();
        [
            SOH, body[0], body[1], body[2], body[3], body[4], body[5], bcc[0], bcc[1], ETX,
        ]
    }

    /// The fields of a received header (control codes and BCC are checked by the receiver).
    pub fn decode_fields(block: &[u8; HEADER_LEN]) -> Header {
        Header {
            len: u16::from_le_bytes([block[1], block[2]]),
            pci: u16::from_le_bytes([block[3], block[4]]),
            first_word: [block[5], block[6]],
        }
    }
}

/// Append frame `index` of `message` to `out`, as it goes on the line.
pub fn encode_frame(message: &[u8], index: usize, check: BlockCheck, out: &mut Vec<u8>) {
    let range = frame_range(message.len(), index);
    let last = range.end == message.len();
    let data = &message[range];
    let fid = frame_id_field(check, index, data).to_le_bytes();
    let bcc = frame_bcc(check, data, fid).to_le_bytes();
    out.reserve(data.len() + FRAME_OVERHEAD);
    out.push(STX);
    out.extend_from_slice(data);
    out.extend_from_slice(&fid);
    out.extend_from_slice(&bcc);
    out.push(if last { ETX } else { ETB });
}

/// The BCC of a frame: over its data and its frame-ID.
pub fn frame_bcc(check: BlockCheck, data: &[u8], fid: [u8; 2]) -> u16 {
    match check {
        BlockCheck::Lrc => lrc(data).wrapping_add(lrc(&fid)),
        BlockCheck::Crc16 => {
            let mut d = CCITT.digest();
            d.update(data);
            d.update(&fid);
            d.finalize()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc16_is_ccitt_and_catches_what_the_lrc_misses() {
        // The standard check value of CRC-16/CCITT-FALSE (IBM-3740).
        assert_eq!(crc16(b"123456789"), 0x29B1);
        // And of the two more checks of CRC-16 mode: CRC-16/ARC and CRC-7/MMC.
        assert_eq!(ARC.checksum(b"123456789"), 0xBB3D);
        assert_eq!(MMC7.checksum(b"123456789"), 0x75);
        // Two flips in one bit column: the sum stays, the CRC does not.
        let a = [0x10, 0x20, 0x30, 0x40];
        let b = [0x11, 0x1F, 0x30, 0x40];
        assert_eq!(lrc(&a), lrc(&b));
        assert_ne!(crc16(&a), crc16(&b));
        let data = [1u8, 2, 3];
        assert_eq!(
            frame_bcc(BlockCheck::Crc16, &data, [0, 0]),
            crc16(&[1, 2, 3, 0, 0])
        );
    }
}
