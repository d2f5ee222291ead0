//! Image pixels as the recorder takes them, their `foxglove.RawImage` encodings, and deterministic PNG
//! encoding (fixed compression and filter, no time or text chunks).

use crate::error::{MmusvError, Result};
use std::borrow::Cow;

/// Borrowed pixels of a `height × width` image, row-major, no padding.
#[derive(Debug, Clone, Copy)]
pub enum Pixels<'a> {
    /// One `u8` per pixel (`mono8`).
    Mono8(&'a [u8]),
    /// Three `u8` per pixel, R G B (`rgb8`).
    Rgb8(&'a [u8]),
    /// One `u16` per pixel (`16UC1`, e.g. depth in millimetres or instance ids).
    Mono16(&'a [u16]),
    /// One `f32` per pixel (`32FC1`, e.g. depth in metres).
    Float32(&'a [f32]),
}

impl Pixels<'_> {
    /// The `foxglove.RawImage` encoding name.
    pub fn encoding(&self) -> &'static str {
        match self {
            Self::Mono8(_) => "mono8",
            Self::Rgb8(_) => "rgb8",
            Self::Mono16(_) => "16UC1",
            Self::Float32(_) => "32FC1",
        }
    }

    /// Values per pixel.
    pub fn channels(&self) -> usize {
        match self {
            Self::Rgb8(_) => 3,
            _ => 1,
        }
    }

    /// Bytes per pixel in the raw (little-endian) layout.
    pub fn bytes_per_pixel(&self) -> u32 {
        match self {
            Self::Mono8(_) => 1,
            Self::Rgb8(_) => 3,
            Self::Mono16(_) => 2,
            Self::Float32(_) => 4,
        }
    }

    fn values(&self) -> usize {
        match self {
            Self::Mono8(v) | Self::Rgb8(v) => v.len(),
            Self::Mono16(v) => v.len(),
            Self::Float32(v) => v.len(),
        }
    }

    /// Checks that the pixels fill `width × height` exactly.
    pub fn check(&self, width: u32, height: u32) -> Result<()> {
        let want = width as usize * height as usize * self.channels();
        if width == 0 || height == 0 || self.values() != want {
            return Err(MmusvError::input(
                "image",
                format!(
                    "{} values do not make a {width}x{height} {} image ({want} values); width and height must be > 0",
                    self.values(),
                    self.encoding()
                ),
            ));
        }
        Ok(())
    }

    /// The pixels as little-endian bytes (the `RawImage` data layout).
    pub fn le_bytes(&self) -> Vec<u8> {
        match self {
            Self::Mono8(v) | Self::Rgb8(v) => v.to_vec(),
            Self::Mono16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Self::Float32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }
}

/// Bytes per pixel of a `foxglove.RawImage` encoding this recorder accepts, or an error listing them.
pub fn raw_bytes_per_pixel(encoding: &str) -> Result<u32> {
    const KNOWN: [(&str, u32); 10] = [
        ("rgb8", 3),
        ("rgba8", 4),
        ("bgr8", 3),
        ("bgra8", 4),
        ("mono8", 1),
        ("8UC1", 1),
        ("mono16", 2),
        ("16UC1", 2),
        ("32FC1", 4),
        ("8UC3", 3),
    ];
    KNOWN.iter().find(|(n, _)| *n == encoding).map(|(_, b)| *b).ok_or_else(|| {
        let names: Vec<&str> = KNOWN.iter().map(|(n, _)| *n).collect();
        MmusvError::input("encoding", format!("{encoding:?} is not supported; use one of {names:?}"))
    })
}

/// Encodes `pixels` as PNG: 8-bit gray, 8-bit RGB or 16-bit gray. Same pixels → same bytes.
pub fn encode_png(width: u32, height: u32, pixels: &Pixels<'_>) -> Result<Vec<u8>> {
    pixels.check(width, height)?;
    let (color, depth, data) = match pixels {
        Pixels::Mono8(v) => (png::ColorType::Grayscale, png::BitDepth::Eight, Cow::Borrowed(*v)),
        Pixels::Rgb8(v) => (png::ColorType::Rgb, png::BitDepth::Eight, Cow::Borrowed(*v)),
        Pixels::Mono16(v) => (
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            Cow::Owned(v.iter().flat_map(|x| x.to_be_bytes()).collect()),
        ),
        Pixels::Float32(_) => {
            return Err(MmusvError::input(
                "image",
                "PNG holds uint8 gray, uint8 RGB or uint16 gray; record float32 images with raw_image",
            ))
        }
    };
    let err = |e: png::EncodingError| MmusvError::input("image", format!("PNG encoding failed: {e}"));
    let mut out = Vec::with_capacity(data.len() / 2 + 1024);
    let mut enc = png::Encoder::new(&mut out, width, height);
    enc.set_color(color);
    enc.set_depth(depth);
    enc.set_compression(png::Compression::Fast);
    let mut writer = enc.write_header().map_err(err)?;
    writer.write_image_data(&data).map_err(err)?;
    writer.finish().map_err(err)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_is_deterministic_and_checks_sizes() -> Result<()> {
        let px: Vec<u8> = (0..4 * 3 * 3).map(|i| (i * 7 % 256) as u8).collect();
        let a = encode_png(4, 3, &Pixels::Rgb8(&px))?;
        let b = encode_png(4, 3, &Pixels::Rgb8(&px))?;
        assert_eq!(a, b);
        assert_eq!(&a[1..4], b"PNG");
        assert!(encode_png(5, 3, &Pixels::Rgb8(&px)).is_err());
        assert!(encode_png(1, 1, &Pixels::Float32(&[0.5])).is_err());
        let depth = encode_png(2, 1, &Pixels::Mono16(&[1, 65535]))?;
        assert!(depth.len() > 8);
        Ok(())
    }

    #[test]
    fn raw_encodings() {
        assert_eq!(raw_bytes_per_pixel("16UC1").ok(), Some(2));
        assert!(raw_bytes_per_pixel("yuv9").is_err());
        assert_eq!(Pixels::Float32(&[1.0]).le_bytes(), 1.0f32.to_le_bytes());
    }
}
