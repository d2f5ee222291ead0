//! Whole-file tests: write one message of every kind, read it back with the `mcap` crate's reader.

use super::*;
use crate::error::{MmusvError, Result};
use foxglove::messages::{CompressedImage, FrameTransforms, PointCloud, RawImage, SceneUpdate};
use prost::Message;
use std::collections::BTreeMap;
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mmusv-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or(());
    let p = dir.join(name);
    let _ = std::fs::remove_file(&p);
    let _ = std::fs::remove_file(partial_path(&p));
    p
}

fn io(e: impl std::fmt::Display) -> MmusvError {
    MmusvError::Io { path: "test".into(), reason: e.to_string() }
}

/// Writes one message of every kind (two frames) into `rec`.
fn write_all(rec: &mut Recorder) -> Result<()> {
    let x = [1.0f32, 2.0, 3.0];
    let ring = [0u16, 1, 2];
    let pts = pack_columns(&[("x", Column::F32(&x)), ("y", Column::F32(&x)), ("ring", Column::U16(&ring))])?;
    let fields: Vec<(&str, PackedType)> = pts.fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let rgb: Vec<u8> = (0..4 * 2 * 3).map(|i| i as u8).collect();
    for k in 0..2u64 {
        let t = k * 100_000_000;
        rec.point_cloud("/usv0/lidar", t, "usv0/lidar", None, &fields, pts.stride, &pts.data)?;
        rec.pixels("/usv0/camera/front/depth", t, "usv0/front", 2, 1, &Pixels::Float32(&[1.5, 2.5]))?;
        rec.png_image("/usv0/camera/front/rgb", t, "usv0/front", 4, 2, &Pixels::Rgb8(&rgb))?;
        rec.frame_transforms(
            "/tf",
            t,
            &[Transform {
                parent: "world".into(),
                child: "usv0".into(),
                translation: [k as f64, 2.0, 0.0],
                rotation: [0.0, 0.0, 0.0, 1.0],
            }],
        )?;
        rec.boxes(
            "/usv0/boxes",
            t,
            "world",
            "targets",
            &[BoxMarker {
                id: "target1".into(),
                center: [10.0, 0.0, 1.0],
                quaternion: [0.0, 0.0, 0.0, 1.0],
                size: [8.0, 3.0, 2.0],
                color: [1.0, 0.0, 0.0, 0.5],
                label: "target1".into(),
            }],
        )?;
        let vessel = VesselState {
            id: "usv0".into(),
            asset: "usv_small".into(),
            role: "usv".into(),
            semantic_class: 11,
            instance_id: 2,
            pose: vec![k as f64, 0.0, 0.0, 0.0, 0.0, 0.5],
            velocity: vec![1.0, 0.0, 0.0],
            box_center: vec![0.0, 0.0, 0.5],
            box_size: vec![5.0, 2.0, 1.5],
        };
        rec.world_state("/world/state", t, &WorldState { frame: k, time_s: t as f64 * 1e-9, vessels: vec![vessel] })?;
        let ann = AgentAnnotations {
            frame: k,
            time_s: t as f64 * 1e-9,
            agent_id: "usv0".into(),
            boxes_lidar: vec![Box3D { target_id: "target1".into(), lidar_points: 42, ..Default::default() }],
            boxes_bev: vec![BevBox { target_id: "target1".into(), x: 1.0, ..Default::default() }],
            boxes_camera: vec![Box2D { camera: "front".into(), occlusion: 0.25, ..Default::default() }],
        };
        rec.annotations("/usv0/annotations", t, &ann)?;
    }
    let meta = BTreeMap::from([("seed".to_string(), "7".to_string())]);
    rec.metadata("scenario", &meta)?;
    rec.attachment("scenario.yaml", "application/yaml", 0, b"name: demo\n")?;
    Ok(())
}

#[test]
fn writes_and_reads_back_every_message() -> Result<()> {
    let path = scratch("all.mcap");
    let mut rec = Recorder::create(&path, false)?;
    write_all(&mut rec)?;
    assert!(rec.partial_path().exists() && !path.exists());
    let summary = rec.finish()?;
    assert!(path.exists() && !partial_path(&path).exists());
    assert_eq!((summary.messages, summary.channels), (14, 7));
    let bytes = std::fs::read(&path).map_err(io)?;
    assert_eq!(summary.bytes, bytes.len() as u64);

    let mut seen: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).map_err(io)? {
        let m = m.map_err(io)?;
        let topic = m.channel.topic.clone();
        let schema = m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default();
        assert_eq!(m.publish_time, m.log_time);
        assert_eq!(m.channel.message_encoding, "protobuf");
        seen.entry(topic.clone()).or_default().push(m.sequence);
        let data: &[u8] = &m.data;
        match schema.as_str() {
            "foxglove.PointCloud" => {
                let pc = PointCloud::decode(data).map_err(io)?;
                assert_eq!(pc.point_stride, 10);
                assert_eq!(pc.fields.iter().map(|f| f.offset).collect::<Vec<_>>(), [0, 4, 8]);
                assert_eq!(&pc.data[10..14], &2.0f32.to_le_bytes());
            }
            "foxglove.RawImage" => {
                let im = RawImage::decode(data).map_err(io)?;
                assert_eq!((im.width, im.height, im.step, im.encoding.as_str()), (2, 1, 8, "32FC1"));
                assert_eq!(&im.data[4..8], &2.5f32.to_le_bytes());
            }
            "foxglove.CompressedImage" => {
                let im = CompressedImage::decode(data).map_err(io)?;
                assert_eq!(im.format, "png");
                assert_eq!(&im.data[1..4], b"PNG");
            }
            "foxglove.FrameTransforms" => {
                let tf = FrameTransforms::decode(data).map_err(io)?;
                assert_eq!(tf.transforms[0].child_frame_id, "usv0");
                let x = tf.transforms[0].translation.map_or(-1.0, |v| v.x);
                assert_eq!(x * 1e8, m.log_time as f64);
            }
            "foxglove.SceneUpdate" => {
                let su = SceneUpdate::decode(data).map_err(io)?;
                let e = &su.entities[0];
                assert!(e.frame_locked && e.cubes.len() == 1 && e.texts[0].text == "target1");
                assert_eq!(e.metadata[0].key, "target1");
            }
            "mmusv.WorldState" => {
                let ws = WorldState::decode(data).map_err(io)?;
                assert_eq!(ws.vessels[0].pose[0] * 1e8, m.log_time as f64);
                assert_eq!(ws.frame * 100_000_000, m.log_time);
            }
            "mmusv.AgentAnnotations" => {
                let a = AgentAnnotations::decode(data).map_err(io)?;
                assert_eq!((a.boxes_lidar[0].lidar_points, a.boxes_camera[0].occlusion), (42, 0.25));
            }
            other => return Err(io(format!("unexpected schema {other} on {topic}"))),
        }
    }
    assert_eq!(seen.len(), 7);
    assert!(seen.values().all(|s| s == &[0, 1]), "{seen:?}");

    let summary = mcap::Summary::read(&bytes).map_err(io)?.ok_or_else(|| io("no summary"))?;
    assert_eq!(summary.metadata_indexes.len(), 1);
    let meta = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).map_err(io)?;
    assert_eq!(meta.metadata.get("seed").map(String::as_str), Some("7"));
    assert_eq!(summary.attachment_indexes.len(), 1);
    let stats = summary.stats.unwrap_or_default();
    assert_eq!((stats.message_start_time, stats.message_end_time), (0, 100_000_000));
    Ok(())
}

#[test]
fn identical_recordings_are_byte_identical() -> Result<()> {
    let mut files = Vec::new();
    for name in ["det_a.mcap", "det_b.mcap"] {
        let path = scratch(name);
        let mut rec = Recorder::create(&path, false)?;
        write_all(&mut rec)?;
        rec.finish()?;
        files.push(std::fs::read(&path).map_err(io)?);
    }
    assert!(!files[0].is_empty());
    assert!(files[0] == files[1]);
    Ok(())
}

#[test]
fn refuses_existing_file_unless_overwrite() -> Result<()> {
    let path = scratch("exists.mcap");
    std::fs::write(&path, b"old").map_err(io)?;
    let err = Recorder::create(&path, false).map(|_| ());
    let Err(MmusvError::Io { path: p, reason }) = err else {
        return Err(io("an existing file was not refused"));
    };
    assert!(p.contains("exists.mcap") && reason.contains("overwrite=True") && reason.contains("--overwrite"));
    let mut rec = Recorder::create(&path, true)?;
    rec.metadata("m", &BTreeMap::new())?;
    // The old file stays until finish succeeds.
    assert_eq!(std::fs::read(&path).map_err(io)?, b"old");
    rec.finish()?;
    assert_eq!(&std::fs::read(&path).map_err(io)?[1..5], b"MCAP");
    Ok(())
}

#[test]
fn dropped_recorder_stays_partial_but_readable() -> Result<()> {
    let path = scratch("dropped.mcap");
    {
        let mut rec = Recorder::create(&path, false)?;
        write_all(&mut rec)?;
    }
    assert!(!path.exists());
    let bytes = std::fs::read(partial_path(&path)).map_err(io)?;
    let count = mcap::MessageStream::new(&bytes).map_err(io)?.filter(|m| m.is_ok()).count();
    assert_eq!(count, 14);
    assert!(mcap::Summary::read(&bytes).map_err(io)?.is_some());

    let path2 = scratch("abandoned.mcap");
    let mut rec = Recorder::create(&path2, false)?;
    write_all(&mut rec)?;
    assert_eq!(rec.abandon()?, partial_path(&path2));
    assert!(!path2.exists() && partial_path(&path2).exists());
    Ok(())
}

#[test]
fn a_second_recorder_on_the_same_name_is_refused() -> Result<()> {
    // Two recorders on one name truncated each other's `.partial`: the first finish renamed a damaged MCAP into
    // place and said it held every message.
    let path = scratch("twice.mcap");
    let mut first = Recorder::create(&path, false)?;
    write_all(&mut first)?;
    let Err(MmusvError::Io { path: named, reason }) = Recorder::create(&path, true) else {
        panic!("a second recorder on a name being written was allowed")
    };
    assert!(named.ends_with("twice.mcap.partial") && reason.contains("another recorder"), "{named}: {reason}");
    let summary = first.finish()?;
    assert_eq!(summary.messages, 14);
    let bytes = std::fs::read(&path).map_err(io)?;
    assert_eq!(mcap::MessageStream::new(&bytes).map_err(io)?.filter(|m| m.is_ok()).count(), 14);
    // Finished (or dropped), the name is free again; a stale `.partial` left by a dropped recorder is emptied.
    drop(Recorder::create(&path, true)?);
    let mut again = Recorder::create(&path, true)?;
    write_all(&mut again)?;
    again.finish()?;
    let bytes = std::fs::read(&path).map_err(io)?;
    assert_eq!(mcap::MessageStream::new(&bytes).map_err(io)?.filter(|m| m.is_ok()).count(), 14);
    Ok(())
}

#[test]
fn rejects_bad_input() -> Result<()> {
    let path = scratch("bad.mcap");
    let mut rec = Recorder::create(&path, false)?;
    let fields = [("x", PackedType::F32)];
    assert!(rec.point_cloud("/p", 0, "f", None, &fields, 4, &[0u8; 6]).is_err());
    assert!(rec.point_cloud("/p", 0, "f", None, &fields, 2, &[0u8; 4]).is_err());
    assert!(rec.point_cloud("", 0, "f", None, &fields, 4, &[0u8; 4]).is_err());
    assert!(rec.raw_image("/i", 0, "f", 2, 2, "yuv9", 2, &[0u8; 4]).is_err());
    assert!(rec.raw_image("/i", 0, "f", 2, 2, "mono8", 2, &[0u8; 3]).is_err());
    assert!(rec.point_cloud("/p", u64::MAX, "f", None, &fields, 4, &[0u8; 4]).is_err());
    rec.point_cloud("/p", 0, "f", Some([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), &fields, 4, &[0u8; 4])?;
    // One topic keeps one schema.
    assert!(rec.raw_image("/p", 0, "f", 1, 1, "mono8", 1, &[0u8]).is_err());
    let bad_q = Transform { parent: "a".into(), child: "b".into(), translation: [0.0; 3], rotation: [0.0; 4] };
    assert!(rec.frame_transforms("/tf", 0, &[bad_q]).is_err());
    // A camera's calibration and 2D boxes: a focal length of 0, a NaN distortion, reversed corners, a colour out
    // of [0, 1] are refused, naming the field.
    let k = [100.0, 100.0, 31.5, 23.5];
    let no_focal = rec.camera_calibration("/c", 0, "c", 64, 48, [0.0, 100.0, 31.5, 23.5], [0.0; 5]);
    assert!(no_focal.is_err_and(|e| e.to_string().contains("intrinsics")));
    assert!(rec.camera_calibration("/c", 0, "c", 64, 48, k, [f64::NAN, 0.0, 0.0, 0.0, 0.0]).is_err());
    let reversed = ImageBox { corners: [10.0, 5.0, 2.0, 8.0], color: [1.0; 4], label: "v".into() };
    assert!(rec.image_boxes("/b", 0, &[reversed]).is_err_and(|e| e.to_string().contains("boxes[0]")));
    let bright = ImageBox { corners: [1.0, 1.0, 2.0, 2.0], color: [2.0, 0.0, 0.0, 1.0], label: String::new() };
    assert!(rec.image_boxes("/b", 0, &[bright]).is_err());
    assert_eq!(rec.finish()?.messages, 1);
    Ok(())
}

/// The opcodes of each chunk's records, in file order (`mcap`'s raw record reader and chunk decoder).
fn chunk_opcodes(bytes: &[u8]) -> Result<Vec<Vec<u8>>> {
    let mut chunks = Vec::new();
    for rec in mcap::read::LinearReader::new(bytes).map_err(io)? {
        if let mcap::records::Record::Chunk { header, data } = rec.map_err(io)? {
            let inner = mcap::read::ChunkReader::new(header, &data).map_err(io)?;
            chunks.push(inner.map(|r| r.map(|r| r.opcode())).collect::<std::result::Result<_, _>>().map_err(io)?);
        }
    }
    Ok(chunks)
}

#[test]
fn the_first_frames_channels_come_first_in_a_chunk_of_their_own() -> Result<()> {
    use mcap::records::op;
    let path = scratch("declared.mcap");
    let mut rec = Recorder::create(&path, false)?;
    write_all(&mut rec)?;
    rec.finish()?;
    let bytes = std::fs::read(&path).map_err(io)?;
    let chunks = chunk_opcodes(&bytes)?;
    assert!(chunks.len() >= 2, "{chunks:?}");
    let (first, rest) = (&chunks[0], &chunks[1..]);
    assert!(first.iter().all(|&o| o == op::SCHEMA || o == op::CHANNEL), "{first:?}");
    assert_eq!(first.iter().filter(|&&o| o == op::CHANNEL).count(), 7);
    assert!(rest.iter().flatten().all(|&o| o == op::MESSAGE), "{rest:?}");
    // The messages in the order written, each channel's sequence from 0: frame 0's held ones too.
    let got: Vec<(String, u32, u64)> = mcap::MessageStream::new(&bytes)
        .map_err(io)?
        .map(|m| m.map(|m| (m.channel.topic.clone(), m.sequence, m.log_time)))
        .collect::<std::result::Result<_, _>>()
        .map_err(io)?;
    assert_eq!(got.len(), 14);
    assert_eq!(got[..7].iter().map(|g| (g.1, g.2)).collect::<Vec<_>>(), vec![(0, 0); 7]);
    assert_eq!(got[7..].iter().map(|g| (g.1, g.2)).collect::<Vec<_>>(), vec![(1, 100_000_000); 7]);
    assert_eq!(got[..7].iter().map(|g| &g.0).collect::<Vec<_>>(), got[7..].iter().map(|g| &g.0).collect::<Vec<_>>());
    Ok(())
}

#[test]
fn messages_held_at_one_log_time_are_written_by_finish_abandon_and_drop() -> Result<()> {
    let frame0 = |rec: &mut Recorder| rec.pixels("/d", 0, "cam", 2, 1, &Pixels::Float32(&[1.5, 2.5]));
    let count = |bytes: &[u8]| -> Result<usize> { Ok(mcap::MessageStream::new(bytes).map_err(io)?.count()) };
    let path = scratch("held.mcap");
    let mut rec = Recorder::create(&path, false)?;
    frame0(&mut rec)?;
    frame0(&mut rec)?;
    rec.pixels("/d", 0, "cam", 2, 1, &Pixels::Mono8(&[1, 2]))?; // RawImage too: the same channel
    rec.finish()?;
    assert_eq!(count(&std::fs::read(&path).map_err(io)?)?, 3);
    for abandon in [true, false] {
        let path = scratch(if abandon { "held_abandoned.mcap" } else { "held_dropped.mcap" });
        let mut rec = Recorder::create(&path, false)?;
        frame0(&mut rec)?;
        if abandon {
            rec.abandon()?;
        } else {
            drop(rec);
        }
        assert_eq!(count(&std::fs::read(partial_path(&path)).map_err(io)?)?, 1);
    }
    // A second schema on a held topic is refused before it is held.
    let mut rec = Recorder::create(&scratch("held_conflict.mcap"), false)?;
    frame0(&mut rec)?;
    let e = rec.png_image("/d", 0, "cam", 1, 1, &Pixels::Rgb8(&[1, 2, 3])).err().map(|e| e.to_string());
    assert!(e.unwrap_or_default().contains("already carries foxglove.RawImage"));
    Ok(())
}
