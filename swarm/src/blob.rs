//! `Blob`: a byte payload that a receiver reads in place, without copying it (zero-copy
//! receive).
//!
//! A message field of type `Blob` is encoded like `serde_bytes` (one length, then the bytes).
//! When the runtime decodes a delivered message of a behaviour with
//! [`crate::Behaviour::zero_copy`], it tells the decoder where the message's bytes live
//! ([`with_source`]): in the multi-process executor the iceoryx2 sample in shared memory, in
//! the in-process executor the tick's radio bytes. A `Blob` decoded from inside those bytes is a
//! view into them that keeps them alive (the sample is returned to its publisher when the last
//! view is dropped); anywhere else (another decoder, a format that hands out owned bytes) it is
//! a copy. Views and copies compare, hash and read the same, so results cannot depend on which
//! one a behaviour got: only the time to receive does.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::cell::RefCell;
use std::ops::Deref;
use std::sync::Arc;

/// Bytes a [`Blob`] can refer into: the owner keeps them valid and unchanged while it lives.
pub trait AsBytes: Send + Sync {
    fn as_bytes(&self) -> &[u8];
}

impl AsBytes for Vec<u8> {
    fn as_bytes(&self) -> &[u8] {
        self
    }
}

/// A byte payload: owned, or a view into received bytes (see the module text).
#[derive(Clone)]
pub struct Blob {
    /// None for an empty blob (no allocation).
    owner: Option<Arc<dyn AsBytes>>,
    at: usize,
    len: usize,
    view: bool,
}

impl Blob {
    /// Whether this blob refers into received bytes rather than holding its own copy.
    pub fn is_view(&self) -> bool {
        self.view
    }

    fn copy_of(v: &[u8]) -> Blob {
        Blob::from(v.to_vec())
    }
}

impl Default for Blob {
    /// An empty blob.
    fn default() -> Blob {
        Blob::from(Vec::new())
    }
}

impl From<Vec<u8>> for Blob {
    fn from(v: Vec<u8>) -> Blob {
        let len = v.len();
        Blob {
            owner: (len > 0).then(|| Arc::new(v) as Arc<dyn AsBytes>),
            at: 0,
            len,
            view: false,
        }
    }
}

impl Deref for Blob {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match &self.owner {
            Some(o) => &o.as_bytes()[self.at..self.at + self.len],
            None => &[],
        }
    }
}

impl AsRef<[u8]> for Blob {
    fn as_ref(&self) -> &[u8] {
        self
    }
}

impl PartialEq for Blob {
    fn eq(&self, other: &Blob) -> bool {
        **self == **other
    }
}

impl Eq for Blob {}

impl std::hash::Hash for Blob {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        (**self).hash(h)
    }
}

impl std::fmt::Debug for Blob {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "Blob({} bytes)", self.len)
    }
}

impl Serialize for Blob {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(self)
    }
}

impl<'de> Deserialize<'de> for Blob {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Blob, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Blob;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("bytes")
            }
            fn visit_borrowed_bytes<E: serde::de::Error>(self, v: &'de [u8]) -> Result<Blob, E> {
                Ok(view(v).unwrap_or_else(|| Blob::copy_of(v)))
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<Blob, E> {
                Ok(Blob::copy_of(v))
            }
            fn visit_byte_buf<E: serde::de::Error>(self, v: Vec<u8>) -> Result<Blob, E> {
                Ok(Blob::from(v))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Blob, A::Error> {
                let mut v = Vec::with_capacity(a.size_hint().unwrap_or(0).min(1 << 20));
                while let Some(b) = a.next_element()? {
                    v.push(b);
                }
                Ok(Blob::from(v))
            }
        }
        d.deserialize_bytes(V)
    }
}

/// The bytes being decoded on this thread, if the runtime said where they live.
struct Source {
    owner: Arc<dyn AsBytes>,
    lo: usize,
    hi: usize,
}

thread_local! {
    static SOURCE: RefCell<Option<Source>> = const { RefCell::new(None) };
}

/// A view of `v` if it lies inside the current source's bytes.
fn view(v: &[u8]) -> Option<Blob> {
    if v.is_empty() {
        return None;
    }
    SOURCE.with(|s| {
        let s = s.borrow();
        let s = s.as_ref()?;
        let p = v.as_ptr() as usize;
        (p >= s.lo && p + v.len() <= s.hi).then(|| Blob {
            owner: Some(s.owner.clone()),
            at: p - s.lo,
            len: v.len(),
            view: true,
        })
    })
}

/// Runs `f` (a decode of bytes inside `owner`'s) with `owner` as the source of `Blob` views.
/// Nests: the previous source is back when `f` returns or unwinds.
pub fn with_source<R>(owner: &Arc<dyn AsBytes>, f: impl FnOnce(&[u8]) -> R) -> R {
    struct Restore(Option<Source>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let prev = self.0.take();
            SOURCE.with(|s| *s.borrow_mut() = prev);
        }
    }
    let bytes = owner.as_bytes();
    let lo = bytes.as_ptr() as usize;
    let src = Source {
        owner: owner.clone(),
        lo,
        hi: lo + bytes.len(),
    };
    let _restore = Restore(SOURCE.with(|s| s.borrow_mut().replace(src)));
    f(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize, Deserialize, PartialEq, Debug)]
    struct Msg {
        stamp: u64,
        data: Blob,
    }

    fn cfg() -> bincode::config::Configuration {
        bincode::config::standard()
    }

    #[test]
    fn encodes_like_a_byte_string() {
        struct Bytes<'a>(&'a [u8]);
        impl Serialize for Bytes<'_> {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_bytes(self.0)
            }
        }
        let b = Blob::from(vec![1, 2, 3]);
        assert_eq!(
            bincode::serde::encode_to_vec(&b, cfg()).unwrap(),
            bincode::serde::encode_to_vec(Bytes(&[1, 2, 3]), cfg()).unwrap()
        );
    }

    #[test]
    fn decoded_inside_a_source_it_is_a_view_that_keeps_the_bytes_alive() {
        let m = Msg {
            stamp: 7,
            data: Blob::from((0..200u8).collect::<Vec<u8>>()),
        };
        let wire: Arc<dyn AsBytes> = Arc::new(bincode::serde::encode_to_vec(&m, cfg()).unwrap());
        let (got, _): (Msg, usize) = with_source(&wire, |b| {
            bincode::serde::borrow_decode_from_slice(b, cfg())
        })
        .unwrap();
        assert_eq!(got, m);
        assert!(got.data.is_view());
        let inside = wire.as_bytes().as_ptr_range();
        assert!(
            inside.contains(&got.data.as_ptr()),
            "the view points into the wire bytes"
        );
        drop(wire);
        assert_eq!(
            &got.data[..3],
            &[0, 1, 2],
            "still readable: the view owns the bytes"
        );
    }

    #[test]
    fn decoded_without_a_source_it_is_a_copy_with_the_same_content() {
        let m = Msg {
            stamp: 1,
            data: Blob::from(vec![9; 50]),
        };
        let wire = bincode::serde::encode_to_vec(&m, cfg()).unwrap();
        let (got, _): (Msg, usize) =
            bincode::serde::borrow_decode_from_slice(&wire, cfg()).unwrap();
        assert!(!got.data.is_view());
        assert_eq!(got, m);
        // The owned decoder hands out owned bytes: a copy too.
        let (got, _): (Msg, usize) = bincode::serde::decode_from_slice(&wire, cfg()).unwrap();
        assert!(!got.data.is_view());
        assert_eq!(got, m);
        // Another source's bytes: not a view of them.
        let other: Arc<dyn AsBytes> = Arc::new(vec![0u8; 10]);
        let (got, _): (Msg, usize) = with_source(&other, |_| {
            bincode::serde::borrow_decode_from_slice(&wire, cfg())
        })
        .unwrap();
        assert!(!got.data.is_view());
    }

    #[test]
    fn sources_nest_and_are_cleared() {
        let a: Arc<dyn AsBytes> = Arc::new(vec![1u8; 8]);
        let b: Arc<dyn AsBytes> = Arc::new(vec![2u8; 8]);
        with_source(&a, |ab| {
            with_source(&b, |bb| assert!(view(bb).is_some() && view(ab).is_none()));
            assert!(view(ab).is_some());
        });
        assert!(view(a.as_bytes()).is_none());
    }
}
