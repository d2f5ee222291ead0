//! One [`Recorder`] method per message kind: Foxglove's well-known schemas (point cloud, raw and PNG image,
//! transforms, 3-D boxes) and the project's own world state and annotations.

use super::image::{encode_png, raw_bytes_per_pixel, Pixels};
use super::own_schema::{AgentAnnotations, WorldState};
use super::points::{packed_offsets, PackedType};
use super::writer::Recorder;
use crate::error::{MmusvError, Result};
use foxglove::messages::{
    points_annotation, CameraCalibration, Color, CompressedImage, CubePrimitive, Duration, FrameTransform,
    FrameTransforms, ImageAnnotations, KeyValuePair, PackedElementField, Point2, PointCloud, PointsAnnotation, Pose,
    Quaternion, RawImage, SceneEntity, SceneUpdate, TextAnnotation, TextPrimitive, Timestamp, Vector3,
};
use prost::bytes::Bytes;

/// One transform for [`Recorder::frame_transforms`]: the pose of `child` in `parent`.
#[derive(Debug, Clone, PartialEq)]
pub struct Transform {
    /// Parent frame id, e.g. `world`.
    pub parent: String,
    /// Child frame id, e.g. `usv0/base_link`.
    pub child: String,
    /// Origin of the child frame in the parent frame, metres.
    pub translation: [f64; 3],
    /// Orientation of the child frame in the parent frame, quaternion `x, y, z, w` (unit).
    pub rotation: [f64; 4],
}

/// Stroke of a 2D box's outline in `foxglove.ImageAnnotations`, pixels.
pub const IMAGE_BOX_PX: f64 = 2.0;
/// Font size of a 2D box's label, pixels.
pub const IMAGE_LABEL_PX: f64 = 12.0;

/// One 2D box of [`Recorder::image_boxes`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImageBox {
    /// `[x0, y0, x1, y1]`, pixels, origin at the top-left corner of the top-left pixel.
    pub corners: [f64; 4],
    /// RGBA in `[0, 1]`.
    pub color: [f32; 4],
    /// Drawn at the top-left corner when not empty.
    pub label: String,
}

/// One 3-D box for [`Recorder::boxes`].
#[derive(Debug, Clone, PartialEq)]
pub struct BoxMarker {
    /// Box id (e.g. the target id), unique within one message; stored in the entity metadata as `id → label`.
    pub id: String,
    /// Box centre in the message frame, metres.
    pub center: [f64; 3],
    /// Box orientation, quaternion `x, y, z, w` (unit).
    pub quaternion: [f64; 4],
    /// Edge lengths along the box's x, y, z axes, metres (finite, `>= 0`).
    pub size: [f64; 3],
    /// RGBA, each 0..1.
    pub color: [f32; 4],
    /// Text drawn above the box; empty for none.
    pub label: String,
}

/// Height of a box label above the box top, metres.
const LABEL_LIFT_M: f64 = 0.5;
/// Label font size, screen pixels.
const LABEL_FONT_PX: f64 = 14.0;

/// Simulation time in nanoseconds as a Foxglove timestamp.
pub fn timestamp(log_time_ns: u64) -> Result<Timestamp> {
    let sec = u32::try_from(log_time_ns / 1_000_000_000).map_err(|_| {
        MmusvError::input("log_time_ns", format!("{log_time_ns} ns is past the 32-bit seconds range of timestamps"))
    })?;
    Ok(Timestamp::new(sec, (log_time_ns % 1_000_000_000) as u32))
}

fn finite(values: &[f64], field: &str) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(MmusvError::input(field, format!("contains NaN or infinity: {values:?}")))
    }
}

/// Checks a quaternion `x, y, z, w` is finite and of unit length (within 1e-3).
fn unit_quaternion(q: &[f64; 4], field: &str) -> Result<Quaternion> {
    finite(q, field)?;
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-3 {
        return Err(MmusvError::input(field, format!("quaternion x, y, z, w must have unit length, got norm {norm}")));
    }
    Ok(Quaternion { x: q[0], y: q[1], z: q[2], w: q[3] })
}

/// Checks an RGBA colour lies in `[0, 1]` and makes it Foxglove's `Color`.
fn rgba(c: &[f32; 4], field: &str) -> Result<Color> {
    if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
        return Err(MmusvError::input(field, format!("color {c:?} must be RGBA, each in [0, 1]")));
    }
    Ok(Color { r: c[0] as f64, g: c[1] as f64, b: c[2] as f64, a: c[3] as f64 })
}

fn vec3(v: &[f64; 3]) -> Vector3 {
    Vector3 { x: v[0], y: v[1], z: v[2] }
}

fn pose(position: &[f64; 3], q: &[f64; 4], field: &str) -> Result<Pose> {
    finite(position, field)?;
    Ok(Pose { position: Some(vec3(position)), orientation: Some(unit_quaternion(q, field)?) })
}

/// A `foxglove.RawImage` of `data`, `height` rows of `step` bytes in `encoding` (checked).
fn raw_message(
    log_time_ns: u64,
    frame_id: &str,
    width: u32,
    height: u32,
    encoding: &str,
    step: u32,
    data: Bytes,
) -> Result<RawImage> {
    let bpp = raw_bytes_per_pixel(encoding)?;
    if width == 0 || height == 0 {
        return Err(MmusvError::input("image", format!("{width}x{height}: width and height must be > 0")));
    }
    if (step as u64) < width as u64 * bpp as u64 || data.len() as u64 != step as u64 * height as u64 {
        return Err(MmusvError::input(
            "image",
            format!(
                "{} bytes do not make {height} rows of step {step} for width {width} {encoding} \
                 (step >= {} and data = step * height)",
                data.len(),
                width as u64 * bpp as u64
            ),
        ));
    }
    Ok(RawImage {
        timestamp: Some(timestamp(log_time_ns)?),
        frame_id: frame_id.to_string(),
        width,
        height,
        encoding: encoding.to_string(),
        step,
        data,
    })
}

/// The `foxglove.RawImage` of `pixels` (encoding from the pixel kind, rows unpadded, little-endian).
pub fn pixels_message(
    log_time_ns: u64,
    frame_id: &str,
    width: u32,
    height: u32,
    pixels: &Pixels<'_>,
) -> Result<RawImage> {
    pixels.check(width, height)?;
    let step = width * pixels.bytes_per_pixel();
    raw_message(log_time_ns, frame_id, width, height, pixels.encoding(), step, Bytes::from(pixels.le_bytes()))
}

/// The `foxglove.CompressedImage` (format `png`) of `pixels`: 8-bit gray, 8-bit RGB or 16-bit gray.
pub fn png_message(
    log_time_ns: u64,
    frame_id: &str,
    width: u32,
    height: u32,
    pixels: &Pixels<'_>,
) -> Result<CompressedImage> {
    let png = encode_png(width, height, pixels)?;
    Ok(CompressedImage {
        timestamp: Some(timestamp(log_time_ns)?),
        frame_id: frame_id.to_string(),
        data: Bytes::from(png),
        format: "png".to_string(),
    })
}

impl Recorder {
    /// Writes a `foxglove.PointCloud`: `fields` packed back to back in each `point_stride`-byte point of
    /// `data` (little-endian; `point_stride` may exceed the fields' total to leave padding). `pose_of_frame`
    /// is the cloud origin in `frame_id` as `x, y, z, qx, qy, qz, qw` (None: identity).
    #[allow(clippy::too_many_arguments)]
    pub fn point_cloud(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        pose_of_frame: Option<[f64; 7]>,
        fields: &[(&str, PackedType)],
        point_stride: u32,
        data: &[u8],
    ) -> Result<()> {
        let (offsets, packed) = packed_offsets(fields);
        if fields.is_empty() || point_stride < packed {
            return Err(MmusvError::input(
                "point_stride",
                format!("{point_stride} bytes cannot hold the {} field(s) of {packed} bytes", fields.len()),
            ));
        }
        if !data.len().is_multiple_of(point_stride as usize) {
            return Err(MmusvError::input(
                "data",
                format!("{} bytes is not a whole number of {point_stride}-byte points", data.len()),
            ));
        }
        let pose = match pose_of_frame {
            Some(p) => Some(pose(&[p[0], p[1], p[2]], &[p[3], p[4], p[5], p[6]], "pose")?),
            None => None,
        };
        let message = PointCloud {
            timestamp: Some(timestamp(log_time_ns)?),
            frame_id: frame_id.to_string(),
            pose,
            point_stride,
            fields: fields
                .iter()
                .zip(offsets)
                .map(|((name, t), offset)| PackedElementField {
                    name: (*name).to_string(),
                    offset,
                    r#type: t.numeric_type() as i32,
                })
                .collect(),
            data: Bytes::copy_from_slice(data),
        };
        self.write(topic, log_time_ns, &message)
    }

    /// Writes a `foxglove.RawImage`; `encoding` is one of `rgb8`, `rgba8`, `bgr8`, `bgra8`, `mono8`, `8UC1`,
    /// `8UC3`, `mono16`, `16UC1`, `32FC1`; `data` is `height` rows of `step` bytes, multi-byte values
    /// little-endian; width and height > 0 (errors name `image`).
    #[allow(clippy::too_many_arguments)]
    pub fn raw_image(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        width: u32,
        height: u32,
        encoding: &str,
        step: u32,
        data: &[u8],
    ) -> Result<()> {
        let message = raw_message(log_time_ns, frame_id, width, height, encoding, step, Bytes::copy_from_slice(data))?;
        self.write(topic, log_time_ns, &message)
    }

    /// Writes `pixels` as a `foxglove.RawImage` (encoding from the pixel kind, rows unpadded).
    pub fn pixels(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        width: u32,
        height: u32,
        pixels: &Pixels<'_>,
    ) -> Result<()> {
        self.write(topic, log_time_ns, &pixels_message(log_time_ns, frame_id, width, height, pixels)?)
    }

    /// Encodes `pixels` as PNG (8-bit gray, 8-bit RGB or 16-bit gray) and writes a `foxglove.CompressedImage`
    /// with format `png`.
    pub fn png_image(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        width: u32,
        height: u32,
        pixels: &Pixels<'_>,
    ) -> Result<()> {
        self.write(topic, log_time_ns, &png_message(log_time_ns, frame_id, width, height, pixels)?)
    }

    /// Writes a `foxglove.FrameTransforms` holding every transform, all stamped `log_time_ns`.
    pub fn frame_transforms(&mut self, topic: &str, log_time_ns: u64, transforms: &[Transform]) -> Result<()> {
        let stamp = timestamp(log_time_ns)?;
        let transforms = transforms
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let field = format!("transforms[{i}]");
                finite(&t.translation, &field)?;
                Ok(FrameTransform {
                    timestamp: Some(stamp),
                    parent_frame_id: t.parent.clone(),
                    child_frame_id: t.child.clone(),
                    translation: Some(vec3(&t.translation)),
                    rotation: Some(unit_quaternion(&t.rotation, &field)?),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        self.write(topic, log_time_ns, &FrameTransforms { transforms })
    }

    /// Writes a `foxglove.SceneUpdate` with one entity `entity_id` in `frame_id` (frame-locked, no lifetime)
    /// holding one cube per box and one billboard text per non-empty label; it replaces the previous entity
    /// with the same id on the topic. A box with an empty or repeated id, a non-finite pose or size, a negative
    /// edge or a colour outside `[0, 1]` is an error naming `boxes[i]`.
    pub fn boxes(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        entity_id: &str,
        boxes: &[BoxMarker],
    ) -> Result<()> {
        let stamp = timestamp(log_time_ns)?;
        let mut cubes = Vec::with_capacity(boxes.len());
        let mut texts = Vec::new();
        let mut metadata = Vec::with_capacity(boxes.len());
        for (i, b) in boxes.iter().enumerate() {
            let field = format!("boxes[{i}]");
            if b.id.is_empty() || metadata.iter().any(|kv: &KeyValuePair| kv.key == b.id) {
                return Err(MmusvError::input(
                    field,
                    format!("id {:?} is empty or repeated; ids must be unique", b.id),
                ));
            }
            finite(&b.size, &field)?;
            if b.size.iter().any(|&v| v < 0.0) {
                return Err(MmusvError::input(field, format!("size {:?} has a negative edge length", b.size)));
            }
            let color = rgba(&b.color, &field)?;
            cubes.push(CubePrimitive {
                pose: Some(pose(&b.center, &b.quaternion, &field)?),
                size: Some(vec3(&b.size)),
                color: Some(color),
            });
            if !b.label.is_empty() {
                let above = [b.center[0], b.center[1], b.center[2] + 0.5 * b.size[2] + LABEL_LIFT_M];
                texts.push(TextPrimitive {
                    pose: Some(pose(&above, &[0.0, 0.0, 0.0, 1.0], &field)?),
                    billboard: true,
                    font_size: LABEL_FONT_PX,
                    scale_invariant: true,
                    color: Some(Color { a: 1.0, ..color }),
                    text: b.label.clone(),
                });
            }
            metadata.push(KeyValuePair { key: b.id.clone(), value: b.label.clone() });
        }
        let entity = SceneEntity {
            timestamp: Some(stamp),
            frame_id: frame_id.to_string(),
            id: entity_id.to_string(),
            lifetime: Some(Duration::new(0, 0)),
            frame_locked: true,
            metadata,
            cubes,
            texts,
            ..Default::default()
        };
        self.write(topic, log_time_ns, &SceneUpdate { deletions: Vec::new(), entities: vec![entity] })
    }

    /// Writes a `foxglove.CameraCalibration` of a `width` × `height` pinhole camera in `frame_id` (its optical
    /// frame): `intrinsics` `[fx, fy, cx, cy]` pixels in OpenCV's (ROS's, Foxglove's) convention, pixel centres at
    /// whole numbers; `distortion` OpenCV's `[k1, k2, p1, p2, k3]` (`plumb_bob`), zeros for none; R = I, P = [K | 0].
    /// Non-finite intrinsics or distortion, or a focal length ≤ 0, are an error naming the field.
    #[allow(clippy::too_many_arguments)]
    pub fn camera_calibration(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        frame_id: &str,
        width: u32,
        height: u32,
        intrinsics: [f64; 4],
        distortion: [f64; 5],
    ) -> Result<()> {
        finite(&intrinsics, "intrinsics")?;
        finite(&distortion, "distortion")?;
        let [fx, fy, cx, cy] = intrinsics;
        if fx <= 0.0 || fy <= 0.0 {
            return Err(MmusvError::input("intrinsics", format!("focal lengths {fx}, {fy} must be > 0 pixels")));
        }
        let message = CameraCalibration {
            timestamp: Some(timestamp(log_time_ns)?),
            frame_id: frame_id.to_string(),
            width,
            height,
            distortion_model: "plumb_bob".into(),
            d: distortion.to_vec(),
            k: vec![fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            r: vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: vec![fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        };
        self.write(topic, log_time_ns, &message)
    }

    /// Writes a `foxglove.ImageAnnotations` of 2D boxes: each an outlined rectangle (`LINE_LOOP` through its four
    /// corners) and, when it has a label, a text at its top-left corner, in pixels with the origin at the top-left
    /// corner of the image's top-left pixel (Foxglove's convention, and mmusv's). A box with non-finite or
    /// reversed corners, or a colour outside `[0, 1]`, is an error naming `boxes[i]`.
    pub fn image_boxes(&mut self, topic: &str, log_time_ns: u64, boxes: &[ImageBox]) -> Result<()> {
        let stamp = timestamp(log_time_ns)?;
        let mut points = Vec::with_capacity(boxes.len());
        let mut texts = Vec::new();
        for (i, b) in boxes.iter().enumerate() {
            let field = format!("boxes[{i}]");
            let [x0, y0, x1, y1] = b.corners;
            finite(&b.corners, &field)?;
            if x1 < x0 || y1 < y0 {
                return Err(MmusvError::input(
                    field,
                    format!("corners {:?} are not [x0, y0, x1, y1], x0 <= x1, y0 <= y1", b.corners),
                ));
            }
            let color = rgba(&b.color, &field)?;
            let corner = |x: f64, y: f64| Point2 { x, y };
            points.push(PointsAnnotation {
                timestamp: Some(stamp),
                r#type: points_annotation::Type::LineLoop as i32,
                points: vec![corner(x0, y0), corner(x1, y0), corner(x1, y1), corner(x0, y1)],
                outline_color: Some(color),
                thickness: IMAGE_BOX_PX,
                ..Default::default()
            });
            if !b.label.is_empty() {
                texts.push(TextAnnotation {
                    timestamp: Some(stamp),
                    position: Some(corner(x0, y0)),
                    text: b.label.clone(),
                    font_size: IMAGE_LABEL_PX,
                    text_color: Some(Color { r: 1.0, g: 1.0, b: 1.0, a: 1.0 }),
                    background_color: Some(Color { a: 0.7, ..color }),
                    ..Default::default()
                });
            }
        }
        let message = ImageAnnotations { timestamp: Some(stamp), points, texts, ..Default::default() };
        self.write(topic, log_time_ns, &message)
    }

    /// Writes the project's own `mmusv.WorldState`.
    pub fn world_state(&mut self, topic: &str, log_time_ns: u64, state: &WorldState) -> Result<()> {
        self.write(topic, log_time_ns, state)
    }

    /// Writes the project's own `mmusv.AgentAnnotations`.
    pub fn annotations(&mut self, topic: &str, log_time_ns: u64, annotations: &AgentAnnotations) -> Result<()> {
        self.write(topic, log_time_ns, annotations)
    }
}
