//! Reading the values of PLY rows in each encoding: whitespace-separated text, or fixed-size
//! binary scalars in either byte order. The element walker in `read` asks a [`RowSource`] for
//! one typed value at a time, or a whole block of fixed-size binary rows.

use super::PlyType;
use crate::pcd::clip;

/// A decoded value.
#[derive(Debug, Clone, Copy)]
pub(super) enum Num {
    I(i64),
    F32(f32),
    F64(f64),
}

impl Num {
    pub(super) fn to_f32(self) -> f32 {
        match self {
            Num::I(v) => v as f32,
            Num::F32(v) => v,
            Num::F64(v) => v as f32,
        }
    }

    pub(super) fn as_f64(self) -> f64 {
        match self {
            Num::I(v) => v as f64,
            Num::F32(v) => f64::from(v),
            Num::F64(v) => v,
        }
    }

    pub(super) fn to_channel(self, ty: PlyType) -> u8 {
        match (self, ty) {
            (Num::I(v), PlyType::UInt16) => (v >> 8).clamp(0, 255) as u8,
            (Num::I(v), _) => v.clamp(0, 255) as u8,
            (v, _) => {
                let f = v.as_f64();
                if f.is_nan() {
                    0
                } else {
                    (f.clamp(0.0, 1.0) * 255.0).round() as u8
                }
            }
        }
    }

    pub(super) fn to_label(self) -> Option<u32> {
        match self {
            Num::I(v) => u32::try_from(v).ok(),
            v => {
                let f = v.as_f64();
                (f.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&f)).then_some(f as u32)
            }
        }
    }
}

/// Why a value could not be read (context is added by the caller).
pub(super) enum Fail {
    Eof,
    Bad { line: usize, token: String },
}

/// Row data in one of the three encodings.
pub(super) trait RowSource {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail>;
    /// Skips `n` items of type `ty`.
    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail>;
    fn remaining(&self) -> usize;
    /// Binary sources: the next `len` bytes at once, with the byte order (`true`: big endian).
    fn block(&mut self, _len: usize) -> Option<(&[u8], bool)> {
        None
    }
}

pub(super) struct Binary<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    pub(super) big_endian: bool,
}

/// Decodes one binary value; `s` holds exactly `ty.size()` bytes (shorter is zero-padded).
pub(super) fn decode_scalar(s: &[u8], ty: PlyType, big_endian: bool) -> Num {
    fn arr<const N: usize>(s: &[u8], big_endian: bool) -> [u8; N] {
        let mut a = [0_u8; N];
        let n = s.len().min(N);
        a[..n].copy_from_slice(&s[..n]);
        if big_endian {
            a.reverse();
        }
        a
    }
    let b = big_endian;
    match ty {
        PlyType::Int8 => Num::I(i64::from(i8::from_le_bytes(arr(s, b)))),
        PlyType::UInt8 => Num::I(i64::from(u8::from_le_bytes(arr(s, b)))),
        PlyType::Int16 => Num::I(i64::from(i16::from_le_bytes(arr(s, b)))),
        PlyType::UInt16 => Num::I(i64::from(u16::from_le_bytes(arr(s, b)))),
        PlyType::Int32 => Num::I(i64::from(i32::from_le_bytes(arr(s, b)))),
        PlyType::UInt32 => Num::I(i64::from(u32::from_le_bytes(arr(s, b)))),
        PlyType::Float32 => Num::F32(f32::from_le_bytes(arr(s, b))),
        PlyType::Float64 => Num::F64(f64::from_le_bytes(arr(s, b))),
    }
}

impl RowSource for Binary<'_> {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail> {
        let s = self
            .data
            .get(self.pos..self.pos + ty.size())
            .ok_or(Fail::Eof)?;
        self.pos += ty.size();
        Ok(decode_scalar(s, ty, self.big_endian))
    }

    fn block(&mut self, len: usize) -> Option<(&[u8], bool)> {
        let s = self.data.get(self.pos..self.pos.checked_add(len)?)?;
        self.pos += len;
        Some((s, self.big_endian))
    }

    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail> {
        let bytes = n.checked_mul(ty.size() as u64).ok_or(Fail::Eof)?;
        if bytes > self.remaining() as u64 {
            return Err(Fail::Eof);
        }
        self.pos += bytes as usize;
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
}

pub(super) struct Ascii<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    pub(super) line: usize,
}

impl<'a> Ascii<'a> {
    fn token(&mut self) -> Option<(&'a [u8], usize)> {
        let data = self.data;
        while let Some(&b) = data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while data.get(self.pos).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.pos += 1;
        }
        (self.pos > start).then(|| (&data[start..self.pos], self.line))
    }
}

fn parse_ascii(tok: &str, ty: PlyType) -> Option<Num> {
    Some(match ty {
        PlyType::Int8 => Num::I(i64::from(tok.parse::<i8>().ok()?)),
        PlyType::UInt8 => Num::I(i64::from(tok.parse::<u8>().ok()?)),
        PlyType::Int16 => Num::I(i64::from(tok.parse::<i16>().ok()?)),
        PlyType::UInt16 => Num::I(i64::from(tok.parse::<u16>().ok()?)),
        PlyType::Int32 => Num::I(i64::from(tok.parse::<i32>().ok()?)),
        PlyType::UInt32 => Num::I(i64::from(tok.parse::<u32>().ok()?)),
        PlyType::Float32 => Num::F32(tok.parse::<f32>().ok()?),
        PlyType::Float64 => Num::F64(tok.parse::<f64>().ok()?),
    })
}

impl RowSource for Ascii<'_> {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail> {
        let (tok, line) = self.token().ok_or(Fail::Eof)?;
        std::str::from_utf8(tok)
            .ok()
            .and_then(|t| parse_ascii(t, ty))
            .ok_or_else(|| Fail::Bad {
                line,
                token: clip(&String::from_utf8_lossy(tok)),
            })
    }

    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail> {
        // Each iteration consumes a token or stops, so this is bounded by the input.
        for _ in 0..n {
            self.value(ty)?;
        }
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
}
