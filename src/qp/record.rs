//! Recorded QP sets: a compact binary file of [`OcpQp`]s, so the QPs a
//! controller meets can be stored once and replayed against every backend.
//!
//! Format (all little-endian): the magic `EMPCQP01`, then per QP the
//! dimensions `nx, nu, N` as `u64` followed by the data as `f64` in this
//! order: `x0, soft_l1, soft_l2`, then per stage `k = 0..N`:
//! `Q, S, R, q, r, A, B, c, u_lower, u_upper, x_lower, x_upper`
//! (matrices column-major), and finally `Q_N, q_N, x_lower_N, x_upper_N`.
//! Infinite bounds are stored as infinities.

use super::OcpQp;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;
use thiserror::Error;

/// File magic and version.
pub const MAGIC: &[u8; 8] = b"EMPCQP01";

/// Largest stage dimension accepted when reading (guards against garbage).
const MAX_DIM: u64 = 1 << 12;
/// Largest horizon accepted when reading.
const MAX_HORIZON: u64 = 1 << 20;

/// Why a QP set could not be read or written.
#[derive(Debug, Error)]
pub enum RecordError {
    /// Underlying I/O failure.
    #[error("QP record I/O: {0}")]
    Io(#[from] std::io::Error),
    /// Not a QP record file (or another version).
    #[error("not an EigenMPC QP record (bad magic)")]
    BadMagic,
    /// The file ends inside a QP.
    #[error("QP record truncated inside QP {0}")]
    Truncated(usize),
    /// Dimensions out of range.
    #[error("QP {index} has invalid dimensions nx = {nx}, nu = {nu}, N = {horizon}")]
    BadDimensions {
        /// Position in the file.
        index: usize,
        /// State dimension read.
        nx: u64,
        /// Control dimension read.
        nu: u64,
        /// Horizon read.
        horizon: u64,
    },
}

/// Appends QPs to a record file.
pub struct QpRecordWriter<W: Write> {
    out: W,
}

impl QpRecordWriter<BufWriter<File>> {
    /// Creates (truncates) `path` and writes the magic.
    pub fn create(path: &Path) -> Result<Self, RecordError> {
        Self::new(BufWriter::new(File::create(path)?))
    }
}

impl<W: Write> QpRecordWriter<W> {
    /// Writes the magic to `out`.
    pub fn new(mut out: W) -> Result<Self, RecordError> {
        out.write_all(MAGIC)?;
        Ok(Self { out })
    }

    /// Appends one QP.
    pub fn write(&mut self, qp: &OcpQp) -> Result<(), RecordError> {
        for d in [qp.nx, qp.nu, qp.horizon] {
            self.out.write_all(&(d as u64).to_le_bytes())?;
        }
        let mut put = |v: &[f64]| -> std::io::Result<()> {
            for x in v {
                self.out.write_all(&x.to_le_bytes())?;
            }
            Ok(())
        };
        put(qp.x0.as_slice())?;
        put(qp.soft_l1.as_slice())?;
        put(qp.soft_l2.as_slice())?;
        for k in 0..qp.horizon {
            put(qp.q[k].as_slice())?;
            put(qp.s[k].as_slice())?;
            put(qp.r[k].as_slice())?;
            put(qp.q_lin[k].as_slice())?;
            put(qp.r_lin[k].as_slice())?;
            put(qp.a[k].as_slice())?;
            put(qp.b[k].as_slice())?;
            put(qp.c[k].as_slice())?;
            put(qp.u_lower[k].as_slice())?;
            put(qp.u_upper[k].as_slice())?;
            put(qp.x_lower[k].as_slice())?;
            put(qp.x_upper[k].as_slice())?;
        }
        let n = qp.horizon;
        put(qp.q[n].as_slice())?;
        put(qp.q_lin[n].as_slice())?;
        put(qp.x_lower[n].as_slice())?;
        put(qp.x_upper[n].as_slice())?;
        Ok(())
    }

    /// Flushes and returns the underlying writer.
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Reads QPs one by one from a record.
pub struct QpRecordReader<R: Read> {
    input: R,
    index: usize,
}

impl QpRecordReader<BufReader<File>> {
    /// Opens `path` and checks the magic.
    pub fn open(path: &Path) -> Result<Self, RecordError> {
        Self::new(BufReader::new(File::open(path)?))
    }
}

impl<R: Read> QpRecordReader<R> {
    /// Checks the magic at the start of `input`.
    pub fn new(mut input: R) -> Result<Self, RecordError> {
        let mut magic = [0u8; 8];
        input
            .read_exact(&mut magic)
            .map_err(|_| RecordError::BadMagic)?;
        if &magic != MAGIC {
            return Err(RecordError::BadMagic);
        }
        Ok(Self { input, index: 0 })
    }

    /// The next QP, `None` at the clean end of the file.
    pub fn next_qp(&mut self) -> Result<Option<OcpQp>, RecordError> {
        let index = self.index;
        let truncated = |e: std::io::Error| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                RecordError::Truncated(index)
            } else {
                RecordError::Io(e)
            }
        };
        let mut first = [0u8; 8];
        // A clean end of file is only allowed before a QP starts.
        let mut got = 0;
        while got < 8 {
            let n = self.input.read(&mut first[got..])?;
            if n == 0 {
                return if got == 0 {
                    Ok(None)
                } else {
                    Err(RecordError::Truncated(index))
                };
            }
            got += n;
        }
        let mut word = [0u8; 8];
        let nx = u64::from_le_bytes(first);
        self.input.read_exact(&mut word).map_err(truncated)?;
        let nu = u64::from_le_bytes(word);
        self.input.read_exact(&mut word).map_err(truncated)?;
        let horizon = u64::from_le_bytes(word);
        if !(1..=MAX_DIM).contains(&nx)
            || !(1..=MAX_DIM).contains(&nu)
            || !(1..=MAX_HORIZON).contains(&horizon)
        {
            return Err(RecordError::BadDimensions {
                index,
                nx,
                nu,
                horizon,
            });
        }
        let (nx, nu, n) = (nx as usize, nu as usize, horizon as usize);
        let mut qp = OcpQp::new(nx, nu, n);
        let input = &mut self.input;
        let mut get = |v: &mut [f64]| -> Result<(), RecordError> {
            for x in v.iter_mut() {
                input.read_exact(&mut word).map_err(truncated)?;
                *x = f64::from_le_bytes(word);
            }
            Ok(())
        };
        get(qp.x0.as_mut_slice())?;
        get(qp.soft_l1.as_mut_slice())?;
        get(qp.soft_l2.as_mut_slice())?;
        for k in 0..n {
            get(qp.q[k].as_mut_slice())?;
            get(qp.s[k].as_mut_slice())?;
            get(qp.r[k].as_mut_slice())?;
            get(qp.q_lin[k].as_mut_slice())?;
            get(qp.r_lin[k].as_mut_slice())?;
            get(qp.a[k].as_mut_slice())?;
            get(qp.b[k].as_mut_slice())?;
            get(qp.c[k].as_mut_slice())?;
            get(qp.u_lower[k].as_mut_slice())?;
            get(qp.u_upper[k].as_mut_slice())?;
            get(qp.x_lower[k].as_mut_slice())?;
            get(qp.x_upper[k].as_mut_slice())?;
        }
        get(qp.q[n].as_mut_slice())?;
        get(qp.q_lin[n].as_mut_slice())?;
        get(qp.x_lower[n].as_mut_slice())?;
        get(qp.x_upper[n].as_mut_slice())?;
        self.index += 1;
        Ok(Some(qp))
    }
}

/// Writes `qps` to `path` as one record file.
pub fn write_qp_set(path: &Path, qps: &[OcpQp]) -> Result<(), RecordError> {
    let mut w = QpRecordWriter::create(path)?;
    for qp in qps {
        w.write(qp)?;
    }
    w.finish()?;
    Ok(())
}

/// Reads every QP of the record file `path`.
pub fn read_qp_set(path: &Path) -> Result<Vec<OcpQp>, RecordError> {
    let mut r = QpRecordReader::open(path)?;
    let mut out = Vec::new();
    while let Some(qp) = r.next_qp()? {
        out.push(qp);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_truncation() {
        let mut qp = OcpQp::new(3, 2, 4);
        let mut v = 0.0;
        let mut fill = |s: &mut [f64]| {
            for x in s {
                v += 0.25;
                *x = v;
            }
        };
        for k in 0..4 {
            fill(qp.a[k].as_mut_slice());
            fill(qp.b[k].as_mut_slice());
            fill(qp.s[k].as_mut_slice());
            fill(qp.u_upper[k].as_mut_slice());
        }
        fill(qp.q[4].as_mut_slice());
        fill(qp.x0.as_mut_slice());
        qp.x_lower[2][1] = -1.5;
        let mut w = QpRecordWriter::new(Vec::new()).unwrap();
        w.write(&qp).unwrap();
        w.write(&qp).unwrap();
        let bytes = w.finish().unwrap();
        let mut r = QpRecordReader::new(&bytes[..]).unwrap();
        for _ in 0..2 {
            let back = r.next_qp().unwrap().unwrap();
            assert_eq!(back.a, qp.a);
            assert_eq!(back.q, qp.q);
            assert_eq!(back.u_upper, qp.u_upper);
            assert_eq!(back.u_lower, qp.u_lower);
            assert_eq!(back.x_lower, qp.x_lower);
            assert_eq!(back.x0, qp.x0);
        }
        assert!(r.next_qp().unwrap().is_none());
        let mut r = QpRecordReader::new(&bytes[..bytes.len() - 3]).unwrap();
        r.next_qp().unwrap();
        assert!(matches!(r.next_qp(), Err(RecordError::Truncated(1))));
        assert!(matches!(
            QpRecordReader::new(&b"NOTAQPFILE"[..]),
            Err(RecordError::BadMagic)
        ));
    }
}
