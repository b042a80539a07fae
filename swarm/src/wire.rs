//! The radio's wire format as behaviours and both executors' receive paths share it: the
//! delivered-message type, the send-side trait of a transport, and the bincode payload codec.

use crate::blob::AsBytes;
use crate::frames::{RadioHeader, BROADCAST};
use serde::de::DeserializeOwned;
#[cfg(test)]
use serde::Serialize;
use std::sync::Arc;

/// A delivered radio message.
#[derive(Debug, Clone, PartialEq)]
pub struct Received<M> {
    pub from: u32,
    pub tick: u64,
    pub seq: u32,
    pub sender_pos: [f64; 2],
    pub unicast: bool,
    pub msg: M,
}

impl<M> Received<M> {
    /// `msg` as delivered with header `h`.
    pub fn new(h: &RadioHeader, msg: M) -> Received<M> {
        Received {
            from: h.sender,
            tick: h.tick,
            seq: h.seq,
            sender_pos: h.sender_pos,
            unicast: h.dest != BROADCAST,
            msg,
        }
    }
}

/// The transport's send side: loan `header.len` bytes, let `fill` write the payload in place,
/// send it with `header`.
pub trait RadioTx {
    fn transmit(&mut self, header: &RadioHeader, fill: &mut dyn FnMut(&mut [u8]));
}

pub(crate) fn bincode_config() -> bincode::config::Configuration {
    bincode::config::standard()
}

/// A radio payload as every receiver decodes it: None if malformed (undecodable, or its length
/// does not match the header).
///
/// It decodes with bincode's borrowing decoder even though `M` owns its data: a byte string
/// or string field is then handed over as a slice of `payload` and copied once into the
/// message (serde's `visit_borrowed_bytes`), where the owning decoder first builds a zeroed
/// `Vec` of it and reads into that (two passes over the bytes; at 1 MiB a fresh zeroed
/// allocation each time). The values decoded are the same.
pub fn decode<M: DeserializeOwned>(h: &RadioHeader, payload: &[u8]) -> Option<M> {
    exact(h, payload, |b| {
        bincode::serde::borrow_decode_from_slice::<M, _>(b, bincode_config())
    })
}

/// [`decode`] of the message at offset `at` of `owner`'s bytes, with `owner` as the source of
/// [`crate::Blob`] views (zero-copy receive).
pub fn decode_in<M: DeserializeOwned>(
    h: &RadioHeader,
    owner: &Arc<dyn AsBytes>,
    at: usize,
) -> Option<M> {
    crate::blob::with_source(owner, |bytes| {
        exact(h, bytes.get(at..)?, |b| {
            bincode::serde::borrow_decode_from_slice::<M, _>(b, bincode_config())
        })
    })
}

/// The header's `len` bytes of `payload` decoded by `dec`, which must use all of them.
fn exact<M>(
    h: &RadioHeader,
    payload: &[u8],
    dec: impl FnOnce(&[u8]) -> Result<(M, usize), bincode::error::DecodeError>,
) -> Option<M> {
    let len = h.len as usize;
    let (msg, used) = dec(payload.get(..len)?).ok()?;
    (used == len).then_some(msg)
}

/// A payload as the runtime encodes it (for tests).
#[cfg(test)]
pub(crate) fn encode<M: Serialize>(msg: &M) -> Vec<u8> {
    bincode::serde::encode_to_vec(msg, bincode_config()).expect("encodable")
}
