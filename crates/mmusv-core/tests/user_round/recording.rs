//! Recording: a recording reads back with the MCAP reader, the recorder refuses bad messages, images and
//! box markers, and the world mesh exports as OBJ and PLY.

use super::common::{box_mesh, ok, refuses, scratch_dir};
use mmusv_core::error::MmusvError;
use mmusv_core::geometry::RigidPose;
use mmusv_core::record::{AgentAnnotations, BoxMarker, Column, Pixels, Recorder, Transform, VesselState, WorldState};
use mmusv_core::scene::Scene;

#[test]
fn a_recording_reads_back_with_the_mcap_reader() {
    let dir = scratch_dir("rec");
    let path = dir.join("run.mcap");
    let mut rec = ok("create", || Recorder::create(&path, false));
    assert!(rec.partial_path().ends_with("run.mcap.partial"));
    assert!(rec.partial_path().exists() && !path.exists(), "written under .partial until finished");
    let x = [1.0f32, 2.0, 3.0];
    let ring = [0u16, 1, 2];
    let packed =
        ok("pack", || mmusv_core::record::pack_columns(&[("x", Column::F32(&x)), ("ring", Column::U16(&ring))]));
    assert_eq!((packed.stride, packed.offsets.clone(), packed.data.len()), (6, vec![0, 4], 18));
    let fields: Vec<(&str, _)> = packed.fields.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    ok("point cloud", || {
        rec.point_cloud("/usv0/lidar", 1_000, "usv0/lidar", None, &fields, packed.stride, &packed.data)
    });
    let rgb = vec![7u8; 4 * 3 * 3];
    ok("png", || rec.png_image("/usv0/cam/rgb", 1_000, "usv0/cam", 4, 3, &Pixels::Rgb8(&rgb)));
    let depth = vec![1.5f32; 12];
    ok("raw", || rec.pixels("/usv0/cam/depth", 1_000, "usv0/cam", 4, 3, &Pixels::Float32(&depth)));
    let tf = Transform {
        parent: "world".into(),
        child: "usv0".into(),
        translation: [1.0, 2.0, 3.0],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    ok("tf", || rec.frame_transforms("/tf", 1_000, std::slice::from_ref(&tf)));
    let bx = BoxMarker {
        id: "t1".into(),
        center: [1.0, 2.0, 0.0],
        quaternion: [0.0, 0.0, 0.0, 1.0],
        size: [4.0, 2.0, 1.5],
        color: [1.0, 0.0, 0.0, 0.5],
        label: "target".into(),
    };
    ok("boxes", || rec.boxes("/boxes", 1_000, "world", "gt", std::slice::from_ref(&bx)));
    let state = WorldState {
        frame: 3,
        time_s: 0.3,
        vessels: vec![VesselState {
            id: "usv0".into(),
            asset: "usv".into(),
            role: "usv".into(),
            semantic_class: 11,
            instance_id: 2,
            pose: vec![1.0, 2.0, 0.1, 0.0, 0.0, 0.5],
            velocity: vec![1.0, 0.0, 0.0],
            box_center: vec![1.0, 2.0, 0.5],
            box_size: vec![5.0, 2.5, 1.5],
        }],
    };
    ok("world state", || rec.world_state("/world", 2_000, &state));
    ok("world state 2", || rec.world_state("/world", 3_000, &WorldState { frame: 4, ..state.clone() }));
    let ann = AgentAnnotations { frame: 3, time_s: 0.3, agent_id: "usv0".into(), ..Default::default() };
    ok("annotations", || rec.annotations("/usv0/annotations", 2_000, &ann));
    let meta: std::collections::BTreeMap<String, String> = [("seed".to_string(), "7".to_string())].into();
    ok("metadata", || rec.metadata("scenario", &meta));
    ok("attachment", || rec.attachment("scenario.yaml", "text/yaml", 0, b"name: x\n"));
    assert_eq!(rec.messages(), 8);
    let summary = ok("finish", || rec.finish());
    assert_eq!((summary.messages, summary.channels), (8, 7));
    assert_eq!(summary.path, path);
    assert!(path.exists() && !mmusv_core::record::partial_path(&path).exists());
    let bytes = std::fs::read(&path).unwrap_or_default();
    assert_eq!(summary.bytes, bytes.len() as u64);

    // Read back.
    let stream =
        ok("mcap stream", || mcap::MessageStream::new(&bytes).map_err(|e| MmusvError::input("mcap", e.to_string())));
    let mut seen = Vec::new();
    for m in stream {
        let m = ok("message", || m.map_err(|e| MmusvError::input("mcap", e.to_string())));
        let schema = m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default();
        assert_eq!(m.log_time, m.publish_time);
        if m.channel.topic == "/world" {
            let decoded = ok("decode", || {
                <WorldState as prost::Message>::decode(m.data.as_ref())
                    .map_err(|e| MmusvError::input("d", e.to_string()))
            });
            let want = if m.sequence == 0 { state.clone() } else { WorldState { frame: 4, ..state.clone() } };
            assert_eq!(decoded, want);
            assert_eq!(m.log_time, if m.sequence == 0 { 2_000 } else { 3_000 });
        }
        if m.channel.topic == "/usv0/annotations" {
            let decoded = ok("decode ann", || {
                <AgentAnnotations as prost::Message>::decode(m.data.as_ref())
                    .map_err(|e| MmusvError::input("d", e.to_string()))
            });
            assert_eq!(decoded, ann);
        }
        seen.push((m.channel.topic.clone(), schema, m.sequence));
    }
    seen.sort();
    let topics: Vec<(&str, &str, u32)> = seen.iter().map(|(t, s, q)| (t.as_str(), s.as_str(), *q)).collect();
    assert_eq!(
        topics,
        vec![
            ("/boxes", "foxglove.SceneUpdate", 0),
            ("/tf", "foxglove.FrameTransforms", 0),
            ("/usv0/annotations", "mmusv.AgentAnnotations", 0),
            ("/usv0/cam/depth", "foxglove.RawImage", 0),
            ("/usv0/cam/rgb", "foxglove.CompressedImage", 0),
            ("/usv0/lidar", "foxglove.PointCloud", 0),
            ("/world", "mmusv.WorldState", 0),
            ("/world", "mmusv.WorldState", 1),
        ]
    );
    let sum = ok("summary", || mcap::Summary::read(&bytes).map_err(|e| MmusvError::input("mcap", e.to_string())));
    let sum = sum.unwrap_or_else(|| unreachable!("the finished file has a summary"));
    assert_eq!(sum.attachment_indexes.len(), 1);
    assert_eq!(sum.metadata_indexes.len(), 1);
    // An existing file is refused without overwrite; a directory is refused.
    refuses("existing file", "run.mcap", || Recorder::create(&path, false));
    refuses("a directory", "rec", || Recorder::create(&dir, true));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_recorder_refuses_bad_messages() {
    let dir = scratch_dir("bad");
    let path = dir.join("bad.mcap");
    let mut rec = ok("create", || Recorder::create(&path, false));
    let q = [0.0, 0.0, 0.0, 1.0];
    refuses("empty topic", "topic", || rec.world_state("", 0, &WorldState::default()));
    ok("first", || rec.world_state("/w", 0, &WorldState::default()));
    refuses("schema clash", "topic", || rec.annotations("/w", 0, &AgentAnnotations::default()));
    refuses("time past u32 seconds", "log_time_ns", || rec.frame_transforms("/tf", u64::MAX, &[]));
    let tf = |translation: [f64; 3], rotation: [f64; 4]| Transform {
        parent: "world".into(),
        child: "a".into(),
        translation,
        rotation,
    };
    refuses("tf NaN translation", "transforms[0]", || rec.frame_transforms("/tf", 0, &[tf([f64::NAN, 0.0, 0.0], q)]));
    refuses("tf zero quaternion", "transforms[1]", || {
        rec.frame_transforms("/tf", 0, &[tf([0.0; 3], q), tf([0.0; 3], [0.0; 4])])
    });
    refuses("tf non-unit quaternion", "transforms[0]", || {
        rec.frame_transforms("/tf", 0, &[tf([0.0; 3], [0.0, 0.0, 0.0, 2.0])])
    });
    let bx = BoxMarker {
        id: "a".into(),
        center: [0.0; 3],
        quaternion: q,
        size: [1.0; 3],
        color: [1.0; 4],
        label: String::new(),
    };
    refuses("repeated box id", "boxes[1]", || rec.boxes("/b", 0, "world", "e", &[bx.clone(), bx.clone()]));
    refuses("empty box id", "boxes[0]", || {
        rec.boxes("/b", 0, "world", "e", &[BoxMarker { id: String::new(), ..bx.clone() }])
    });
    refuses("box NaN size", "boxes[0]", || {
        rec.boxes("/b", 0, "world", "e", &[BoxMarker { size: [1.0, f64::NAN, 1.0], ..bx.clone() }])
    });
    refuses("box inf centre", "boxes[0]", || {
        rec.boxes("/b", 0, "world", "e", &[BoxMarker { center: [f64::INFINITY, 0.0, 0.0], ..bx.clone() }])
    });
    // Images.
    refuses("png zero width", "image", || rec.png_image("/i", 0, "c", 0, 3, &Pixels::Mono8(&[])));
    refuses("png short data", "image", || rec.png_image("/i", 0, "c", 4, 3, &Pixels::Mono8(&[0; 11])));
    refuses("png float", "image", || rec.png_image("/i", 0, "c", 1, 1, &Pixels::Float32(&[0.5])));
    refuses("pixels zero height", "image", || rec.pixels("/i2", 0, "c", 3, 0, &Pixels::Mono16(&[])));
    refuses("raw unknown encoding", "encoding", || rec.raw_image("/r", 0, "c", 1, 1, "yuv9", 1, &[0]));
    refuses("raw step too small", "image", || rec.raw_image("/r", 0, "c", 4, 1, "rgb8", 11, &[0; 11]));
    refuses("raw data short", "image", || rec.raw_image("/r", 0, "c", 4, 2, "mono8", 4, &[0; 7]));
    // Point clouds.
    refuses("cloud no fields", "point_stride", || rec.point_cloud("/p", 0, "l", None, &[], 4, &[0; 4]));
    let f = [("x", mmusv_core::record::PackedType::F32)];
    refuses("cloud stride too small", "point_stride", || rec.point_cloud("/p", 0, "l", None, &f, 3, &[0; 3]));
    refuses("cloud ragged data", "data", || rec.point_cloud("/p", 0, "l", None, &f, 4, &[0; 6]));
    refuses("cloud NaN pose", "pose", || {
        rec.point_cloud("/p", 0, "l", Some([f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), &f, 4, &[0; 4])
    });
    refuses("pack no columns", "columns", || mmusv_core::record::pack_columns(&[]));
    refuses("pack ragged", "columns[1]", || {
        mmusv_core::record::pack_columns(&[("x", Column::F32(&[1.0, 2.0])), ("y", Column::F32(&[1.0]))])
    });
    refuses("unknown packed type", "my_type", || mmusv_core::record::PackedType::parse("float128", "my_type"));
    // The refused calls wrote nothing.
    assert_eq!(rec.messages(), 1);
    let s = ok("finish", || rec.finish());
    assert_eq!(s.messages, 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn raw_images_of_zero_size_are_refused_like_the_other_image_calls() {
    // `pixels` and `png_image` refuse a 0-pixel image ("width and height must be > 0"); `raw_image` should too.
    let dir = scratch_dir("raw0");
    let mut rec = ok("create", || Recorder::create(&dir.join("r.mcap"), false));
    refuses("raw 0 × 0", "image", || rec.raw_image("/r", 0, "c", 0, 0, "mono8", 0, &[]));
    refuses("raw 0 × 5", "image", || rec.raw_image("/r", 0, "c", 0, 5, "mono8", 0, &[]));
    let _ = rec.abandon();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn box_markers_refuse_negative_sizes_and_colours_outside_0_1() {
    // `BoxMarker::size` is "edge lengths, metres" and `color` "RGBA, each 0..1".
    let dir = scratch_dir("box");
    let mut rec = ok("create", || Recorder::create(&dir.join("b.mcap"), false));
    let bx = BoxMarker {
        id: "a".into(),
        center: [0.0; 3],
        quaternion: [0.0, 0.0, 0.0, 1.0],
        size: [1.0; 3],
        color: [1.0; 4],
        label: String::new(),
    };
    refuses("negative size", "boxes[0]", || {
        rec.boxes("/b", 0, "w", "e", &[BoxMarker { size: [-1.0, 1.0, 1.0], ..bx.clone() }])
    });
    refuses("NaN colour", "boxes[0]", || {
        rec.boxes("/b", 0, "w", "e", &[BoxMarker { color: [f32::NAN, 0.0, 0.0, 1.0], ..bx.clone() }])
    });
    refuses("colour 2", "boxes[0]", || {
        rec.boxes("/b", 0, "w", "e", &[BoxMarker { color: [2.0, 0.0, 0.0, 1.0], ..bx.clone() }])
    });
    let _ = rec.abandon();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_world_mesh_exports_as_obj_and_ply() {
    let mut scene = Scene::new();
    let m = scene.add_mesh(ok("box", || box_mesh("b", [1.0, 2.0, 3.0], 4)));
    ok("a", || scene.add_instance(m, RigidPose::from_xyz_rpy([10.0, 0.0, 0.0], [0.0; 3]), None));
    ok("b", || scene.add_instance(m, RigidPose::IDENTITY, Some(9)));
    let dir = scratch_dir("export");
    let obj = dir.join("w.obj");
    let fmt = ok("format", || mmusv_core::export::MeshFormat::from_path(&obj));
    ok("write obj", || mmusv_core::export::write_world_mesh(&scene.world_mesh(), &obj, fmt));
    let text = std::fs::read_to_string(&obj).unwrap_or_default();
    assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 16);
    assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 24);
    assert!(text.contains("g instance_0") && text.contains("g instance_1"));
    let xs: Vec<f64> = text
        .lines()
        .filter(|l| l.starts_with("v "))
        .filter_map(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        .collect();
    assert!(xs[..8].iter().all(|x| (9.0..=11.0).contains(x)), "instance 0 moved to x = 10 (world frame)");
    let ply = dir.join("w.PLY");
    let fmt = ok("format ply", || mmusv_core::export::MeshFormat::from_path(&ply));
    ok("write ply", || mmusv_core::export::write_world_mesh(&scene.world_mesh(), &ply, fmt));
    let bytes = std::fs::read(&ply).unwrap_or_default();
    let header_end = bytes.windows(11).position(|w| w == b"end_header\n").map_or(0, |p| p + 11);
    assert!(header_end > 0);
    // 16 vertices × 12 bytes + 24 faces × (1 + 12 + 2 + 4) bytes.
    assert_eq!(bytes.len() - header_end, 16 * 12 + 24 * 19);
    refuses("unknown extension", "path", || mmusv_core::export::MeshFormat::from_path(std::path::Path::new("w.stl")));
    refuses("no extension", "path", || mmusv_core::export::MeshFormat::from_path(std::path::Path::new("w")));
    let missing = dir.join("no/such/dir/w.obj");
    refuses("unwritable path", "w.obj", || {
        mmusv_core::export::write_world_mesh(&scene.world_mesh(), &missing, mmusv_core::export::MeshFormat::Obj)
    });
    let _ = std::fs::remove_dir_all(&dir);
}
