//! Images encoded in parallel, outside the recorder: [`encode_images`] turns a list of images (PNG or raw)
//! into [`EncodedMessage`]s on the recorder's own thread pool, then [`Recorder::write_messages`] appends them
//! in list order. Only the append needs the recorder, so a caller that guards it with a lock holds the lock
//! for the append alone.
//!
//! The messages are the ones [`Recorder::png_image`] and [`Recorder::pixels`] write, in the same order, so the
//! file has the same bytes as with one call per image.
//!
//! Why a pool of its own: the recording of frame k runs while the sensors of frame k+1 keep rayon's global pool
//! busy, and rayon's workers take work injected from outside the pool only when they have none of their own;
//! on the global pool the encoding would wait for the capture to end.

use super::image::Pixels;
use super::messages::{pixels_message, png_message};
use super::writer::{EncodedMessage, Recorder};
use crate::error::{MmusvError, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// How one image is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// `foxglove.CompressedImage`, PNG (8-bit gray, 8-bit RGB or 16-bit gray).
    Png,
    /// `foxglove.RawImage` (encoding from the pixel kind).
    Raw,
}

/// One image of a batch: where it goes, its pixels and how it is stored.
#[derive(Debug, Clone, Copy)]
pub struct ImageJob<'a> {
    /// Topic, e.g. `/usv_1/camera/front/rgb`.
    pub topic: &'a str,
    /// Frame id of the image.
    pub frame_id: &'a str,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// The pixels, row-major.
    pub pixels: Pixels<'a>,
    /// PNG or raw.
    pub format: ImageFormat,
}

/// The recorder's encoding pool: as many threads as the pool of the work around it, made once per process
/// ([`crate::threads::per_process`]: a forked child makes its own).
fn encode_pool() -> Option<Arc<rayon::ThreadPool>> {
    static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);
    crate::threads::per_process(&POOL, || {
        rayon::ThreadPoolBuilder::new()
            .num_threads(rayon::current_num_threads())
            .thread_name(|i| format!("mmusv-encode-{i}"))
    })
}

fn encode_one(log_time_ns: u64, job: &ImageJob<'_>) -> Result<EncodedMessage> {
    let (t, f, w, h, px) = (log_time_ns, job.frame_id, job.width, job.height, &job.pixels);
    match job.format {
        ImageFormat::Png => EncodedMessage::encode(job.topic, &png_message(t, f, w, h, px)?),
        ImageFormat::Raw => EncodedMessage::encode(job.topic, &pixels_message(t, f, w, h, px)?),
    }
}

/// Encodes every image of `jobs` (stamped `log_time_ns`) in parallel and returns the messages in job order;
/// the first bad image (in job order) is the error, and then nothing is returned to write.
pub fn encode_images(log_time_ns: u64, jobs: &[ImageJob<'_>]) -> Result<Vec<EncodedMessage>> {
    let run = || jobs.par_iter().with_max_len(1).map(|job| encode_one(log_time_ns, job)).collect();
    match encode_pool() {
        Some(pool) => pool.install(run),
        None => run(), // no thread could be made for the pool: the global pool encodes them instead
    }
}

impl Recorder {
    /// Writes `messages` (from [`encode_images`] or [`EncodedMessage::encode`]) in order, all at
    /// `log_time_ns`. Every topic is checked first ([`Recorder::check_topic`], and one schema per topic within
    /// the batch), so a refused batch writes nothing.
    pub fn write_messages(&mut self, log_time_ns: u64, messages: &[EncodedMessage]) -> Result<()> {
        let mut schemas: BTreeMap<&str, &str> = BTreeMap::new();
        for m in messages {
            self.check_topic(&m.topic, &m.schema.name)?;
            let first = *schemas.entry(&m.topic).or_insert(&m.schema.name);
            if first != m.schema.name {
                return Err(MmusvError::input(
                    "topic",
                    format!("{} gets both {first} and {} in one batch", m.topic, m.schema.name),
                ));
            }
        }
        messages.iter().try_for_each(|m| self.write_message(log_time_ns, m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::partial_path;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("mmusv-batch-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or(());
        let p = dir.join(name);
        let _ = std::fs::remove_file(&p);
        let _ = std::fs::remove_file(partial_path(&p));
        p
    }

    #[test]
    fn a_batch_writes_the_bytes_of_one_call_per_image() -> Result<()> {
        let rgb: Vec<u8> = (0..40 * 30 * 3).map(|i| (i * 31 % 251) as u8).collect();
        let ids: Vec<u16> = (0..40 * 30).map(|i| (i % 7) as u16 * 1000).collect();
        let depth: Vec<f32> = (0..40 * 30).map(|i| if i % 5 == 0 { f32::INFINITY } else { i as f32 * 0.5 }).collect();
        let jobs = [
            ImageJob {
                topic: "/a/rgb",
                frame_id: "a",
                width: 40,
                height: 30,
                pixels: Pixels::Rgb8(&rgb),
                format: ImageFormat::Png,
            },
            ImageJob {
                topic: "/a/depth",
                frame_id: "a",
                width: 40,
                height: 30,
                pixels: Pixels::Float32(&depth),
                format: ImageFormat::Raw,
            },
            ImageJob {
                topic: "/a/ids",
                frame_id: "a",
                width: 40,
                height: 30,
                pixels: Pixels::Mono16(&ids),
                format: ImageFormat::Png,
            },
        ];
        let (one, batch) = (scratch("one.mcap"), scratch("batch.mcap"));
        let mut r1 = Recorder::create(&one, false)?;
        let mut r2 = Recorder::create(&batch, false)?;
        for k in 0..3u64 {
            let t = k * 200_000_000;
            for j in &jobs {
                match j.format {
                    ImageFormat::Png => r1.png_image(j.topic, t, j.frame_id, j.width, j.height, &j.pixels)?,
                    ImageFormat::Raw => r1.pixels(j.topic, t, j.frame_id, j.width, j.height, &j.pixels)?,
                }
            }
            let encoded = encode_images(t, &jobs)?;
            assert_eq!(encoded.iter().map(|m| m.topic.as_str()).collect::<Vec<_>>(), ["/a/rgb", "/a/depth", "/a/ids"]);
            r2.write_messages(t, &encoded)?;
        }
        r1.finish()?;
        r2.finish()?;
        let (a, b) = (std::fs::read(&one), std::fs::read(&batch));
        assert!(matches!((&a, &b), (Ok(x), Ok(y)) if x == y && x.len() > 1000), "the files differ");
        Ok(())
    }

    #[test]
    fn a_bad_image_fails_the_whole_batch() {
        let px = [0u8; 12];
        let ok = ImageJob {
            topic: "/ok",
            frame_id: "f",
            width: 2,
            height: 2,
            pixels: Pixels::Rgb8(&px),
            format: ImageFormat::Png,
        };
        let float_png = ImageJob { pixels: Pixels::Float32(&[1.0; 4]), topic: "/bad", ..ok };
        let wrong_size = ImageJob { width: 3, ..ok };
        assert!(encode_images(0, &[ok, float_png]).is_err());
        assert!(encode_images(0, &[ok, wrong_size]).is_err());
        assert!(encode_images(0, &[ok, ok]).is_ok_and(|m| m.len() == 2));
    }

    #[test]
    fn a_refused_batch_writes_nothing() -> Result<()> {
        let px = [7u8; 12];
        let png = ImageJob {
            topic: "/a",
            frame_id: "f",
            width: 2,
            height: 2,
            pixels: Pixels::Rgb8(&px),
            format: ImageFormat::Png,
        };
        let path = scratch("refused.mcap");
        let mut rec = Recorder::create(&path, false)?;
        let empty_topic = encode_images(0, &[png, ImageJob { topic: "", ..png }])?;
        assert!(rec.write_messages(0, &empty_topic).is_err());
        let mixed = encode_images(0, &[png, ImageJob { format: ImageFormat::Raw, ..png }])?;
        assert!(rec.write_messages(0, &mixed).is_err());
        assert_eq!(rec.messages(), 0);
        rec.write_messages(0, &encode_images(0, &[png])?)?;
        let raw_on_png =
            encode_images(1, &[ImageJob { topic: "/b", ..png }, ImageJob { format: ImageFormat::Raw, ..png }])?;
        assert!(rec.write_messages(1, &raw_on_png).is_err());
        assert_eq!(rec.messages(), 1);
        rec.finish()?;
        Ok(())
    }
}
