//! FMU state save and restore (`fmi2GetFMUstate` ... `fmi2DeSerializeFMUstate`):
//! one versioned byte form, used both in memory and on disk, so that a state
//! restored in the same instance, in a fresh instance or in another process
//! goes through the same checks.
//!
//! Layout (little endian):
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `EMPCSTAT` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 2 | GUID length `g` |
//! | `g` | GUID of the FMU that saved it (ASCII) |
//! | 8 | payload length `p` |
//! | 4 | CRC-32 (IEEE) of the payload |
//! | `p` | payload: the instance snapshot, postcard-encoded |
//!
//! A buffer from another FMU or another build (GUID), another format
//! version, or a truncated or corrupt one is refused with the reason.

use crate::model::{Experiment, ModelError, State};
use crate::variables::Value;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::sync::Mutex;

/// First bytes of every serialized FMU state.
pub const MAGIC: [u8; 8] = *b"EMPCSTAT";

/// Version of the layout and of the snapshot encoding. A build that changes
/// either increments it (and the GUID changes with any variable table).
/// 2: the controller's reference is a variant and its guide (line or chart).
pub const FORMAT_VERSION: u32 = 2;

/// Largest serialized state accepted (bytes): far above any real state
/// (tens of kilobytes), small enough that a corrupt length cannot make the
/// FMU allocate without bound.
pub const MAX_STATE_BYTES: usize = 64 << 20;

/// An FMU state handed to the host as `fmi2FMUstate`: its serialized form.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FmuState {
    pub bytes: Vec<u8>,
}

impl FmuState {
    /// The serialized form (what `fmi2SerializeFMUstate` writes).
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// Encodes a model's state for [`crate::Model::save_state`] (the same
/// exact binary form as the rest of the snapshot).
pub fn encode_model<T: Serialize>(state: &T) -> Result<Vec<u8>, ModelError> {
    postcard::to_allocvec(state)
        .map_err(|e| ModelError::Error(format!("cannot encode the model state: {e}")))
}

/// Decodes a model's state in [`crate::Model::restore_state`]; trailing
/// bytes are an error.
pub fn decode_model<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, ModelError> {
    match postcard::take_from_bytes(bytes) {
        Ok((state, [])) => Ok(state),
        Ok((_, rest)) => Err(ModelError::Error(format!(
            "malformed model state: {} trailing bytes",
            rest.len()
        ))),
        Err(e) => Err(ModelError::Error(format!("malformed model state: {e}"))),
    }
}

/// What an instance saves: its state machine, values and time, and the
/// model's own bytes.
#[derive(Serialize, Deserialize, Debug)]
pub struct Snapshot {
    pub state: State,
    pub values: Vec<Value>,
    pub experiment: Experiment,
    pub time: f64,
    pub last_successful_time: f64,
    pub terminate_requested: bool,
    pub model: Option<ModelSnapshot>,
}

/// The model part of a snapshot: the values it was initialized from (a
/// fresh instance rebuilds it from them) and what it saved.
#[derive(Serialize, Deserialize, Debug, PartialEq)]
pub struct ModelSnapshot {
    pub initial_values: Vec<Value>,
    pub state: Vec<u8>,
}

/// The serialized form of an instance `snapshot` of the FMU with `guid`.
pub fn encode_snapshot(guid: &str, snapshot: &Snapshot) -> Result<Vec<u8>, String> {
    let payload =
        postcard::to_allocvec(snapshot).map_err(|e| format!("cannot encode the state: {e}"))?;
    Ok(encode(guid, &payload))
}

/// The instance snapshot of a serialized state of the FMU with `guid`
/// (header, checksum and payload checked).
pub fn decode_snapshot(guid: &str, bytes: &[u8]) -> Result<Snapshot, String> {
    let payload = decode(guid, bytes)?;
    postcard::from_bytes(payload).map_err(|e| format!("malformed state payload: {e}"))
}

const HEADER_FIXED: usize = 8 + 4 + 2 + 8 + 4;

/// The serialized form of `payload` for the FMU with `guid`.
pub fn encode(guid: &str, payload: &[u8]) -> Vec<u8> {
    let g = guid.as_bytes();
    let mut out = Vec::with_capacity(HEADER_FIXED + g.len() + payload.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(g.len() as u16).to_le_bytes());
    out.extend_from_slice(g);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out.extend_from_slice(payload);
    out
}

/// Checks the header of a serialized state and returns its payload.
pub fn decode<'a>(guid: &str, bytes: &'a [u8]) -> Result<&'a [u8], String> {
    if bytes.len() > MAX_STATE_BYTES {
        return Err(format!(
            "{} bytes is more than the largest FMU state accepted ({MAX_STATE_BYTES})",
            bytes.len()
        ));
    }
    let mut rest = bytes;
    let mut take = |n: usize, what: &str| -> Result<&'a [u8], String> {
        if rest.len() < n {
            return Err(format!(
                "truncated: {} bytes end inside the {what}",
                bytes.len()
            ));
        }
        let (head, tail) = rest.split_at(n);
        rest = tail;
        Ok(head)
    };
    if take(8, "magic number")? != MAGIC {
        return Err("not an EigenMPC FMU state (wrong magic number)".into());
    }
    let version = u32::from_le_bytes(take(4, "format version")?.try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}; this FMU reads version {FORMAT_VERSION}"
        ));
    }
    let g = u16::from_le_bytes(take(2, "GUID length")?.try_into().expect("2 bytes")) as usize;
    let saved_guid = take(g, "GUID")?;
    if saved_guid != guid.as_bytes() {
        return Err(format!(
            "saved by the FMU with GUID {}, this is {guid} (another FMU or another build)",
            String::from_utf8_lossy(saved_guid)
        ));
    }
    let length = u64::from_le_bytes(take(8, "payload length")?.try_into().expect("8 bytes"));
    let crc = u32::from_le_bytes(take(4, "checksum")?.try_into().expect("4 bytes"));
    if rest.len() as u64 != length {
        return Err(format!(
            "truncated or padded: the header announces {length} payload bytes, {} follow",
            rest.len()
        ));
    }
    if crc32fast::hash(rest) != crc {
        return Err("checksum mismatch: the state is corrupt".into());
    }
    Ok(rest)
}

/// Addresses of the live `FmuState`s this library handed out: a pointer
/// the host passes back is used only if it is one of them (a freed or
/// foreign pointer is an error, not a crash).
static LIVE: Mutex<BTreeSet<usize>> = Mutex::new(BTreeSet::new());

fn live() -> std::sync::MutexGuard<'static, BTreeSet<usize>> {
    // A panic while holding the lock leaves the set consistent (insert and
    // remove do not panic half-way).
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Hands `state` to the host (the pointer is registered as live).
pub fn into_raw(state: FmuState) -> *mut FmuState {
    let p = Box::into_raw(Box::new(state));
    live().insert(p as usize);
    p
}

/// Whether `p` is a live state of this library.
pub fn is_live(p: *const FmuState) -> bool {
    live().contains(&(p as usize))
}

/// Frees a live state; `false` if `p` is not one. Safe for any pointer: only
/// one registered by [`into_raw`] (and not freed since) is dereferenced.
#[allow(clippy::not_unsafe_ptr_arg_deref)]
pub fn free(p: *mut FmuState) -> bool {
    if !live().remove(&(p as usize)) {
        return false;
    }
    // SAFETY: `p` came from `into_raw` and was live until just now.
    drop(unsafe { Box::from_raw(p) });
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trip_and_every_field_is_checked() {
        let payload = b"payload bytes".to_vec();
        let bytes = encode("{guid-1}", &payload);
        assert_eq!(decode("{guid-1}", &bytes).unwrap(), &payload[..]);
        let e = decode("{guid-2}", &bytes).unwrap_err();
        assert!(e.contains("GUID {guid-1}"), "{e}");
        let mut bad = bytes.clone();
        bad[0] ^= 1;
        assert!(decode("{guid-1}", &bad).unwrap_err().contains("magic"));
        let mut bad = bytes.clone();
        bad[8] = 9;
        assert!(decode("{guid-1}", &bad).unwrap_err().contains("version 9"));
        let mut bad = bytes.clone();
        *bad.last_mut().unwrap() ^= 0x10;
        assert!(decode("{guid-1}", &bad).unwrap_err().contains("checksum"));
        for n in 0..bytes.len() {
            let e = decode("{guid-1}", &bytes[..n]).unwrap_err();
            assert!(e.contains("truncated"), "{n}: {e}");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(decode("{guid-1}", &long).unwrap_err().contains("padded"));
    }

    #[test]
    fn only_live_pointers_are_freed() {
        let p = into_raw(FmuState { bytes: vec![1, 2] });
        assert!(is_live(p));
        assert!(free(p));
        assert!(!is_live(p));
        assert!(!free(p), "a second free is refused");
    }
}
