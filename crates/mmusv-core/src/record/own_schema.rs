//! The project's own protobuf messages, `mmusv.WorldState` and `mmusv.AgentAnnotations`, as prost structs,
//! and the `FileDescriptorSet` that describes them, built in code (no `protoc` at build time).
//!
//! The descriptor and the `#[prost(...)]` attributes below must agree field by field (name, number, type,
//! label); `tests` in this module check the descriptor and the Python tests decode every field with it.
//! proto3, so repeated doubles are packed. Units: metres, seconds, radians; world frame x east, y north, z up.

use foxglove::{Encode, Schema};
use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};
use std::sync::OnceLock;

/// Protobuf package of the own messages.
pub const PACKAGE: &str = "mmusv";
/// File name the messages are declared in inside the descriptor set.
pub const PROTO_FILE: &str = "mmusv/record.proto";

/// One vessel (USV or target) in the world at one frame.
#[derive(Clone, PartialEq, Message)]
pub struct VesselState {
    /// Vessel id from the scenario, e.g. `usv0`, `target3`.
    #[prost(string, tag = "1")]
    pub id: String,
    /// Asset (hull model) name from the vessel library.
    #[prost(string, tag = "2")]
    pub asset: String,
    /// Role: `usv` or `target`.
    #[prost(string, tag = "3")]
    pub role: String,
    /// Semantic class (see `mmusv.classes`).
    #[prost(uint32, tag = "4")]
    pub semantic_class: u32,
    /// Scene instance id of the hull.
    #[prost(uint32, tag = "5")]
    pub instance_id: u32,
    /// `x, y, z, roll, pitch, yaw` in the world frame, metres and radians.
    #[prost(double, repeated, tag = "6")]
    pub pose: Vec<f64>,
    /// `vx, vy, vz` in the world frame, m/s.
    #[prost(double, repeated, tag = "7")]
    pub velocity: Vec<f64>,
    /// Centre of the oriented bounding box in the world frame, metres.
    #[prost(double, repeated, tag = "8")]
    pub box_center: Vec<f64>,
    /// `length, beam, height` of the bounding box, metres.
    #[prost(double, repeated, tag = "9")]
    pub box_size: Vec<f64>,
}

/// Ground truth of the whole world at one frame.
#[derive(Clone, PartialEq, Message)]
pub struct WorldState {
    /// Frame index `k`.
    #[prost(uint64, tag = "1")]
    pub frame: u64,
    /// Simulation time, seconds.
    #[prost(double, tag = "2")]
    pub time_s: f64,
    /// Every vessel, USVs included.
    #[prost(message, repeated, tag = "3")]
    pub vessels: Vec<VesselState>,
}

/// A 3-D box label in an agent's LiDAR frame.
#[derive(Clone, PartialEq, Message)]
pub struct Box3D {
    /// Id of the labelled vessel.
    #[prost(string, tag = "1")]
    pub target_id: String,
    /// Scene instance id of the labelled vessel.
    #[prost(uint32, tag = "2")]
    pub instance_id: u32,
    /// Semantic class of the labelled vessel.
    #[prost(uint32, tag = "3")]
    pub semantic_class: u32,
    /// Box centre `x, y, z`, metres, LiDAR frame.
    #[prost(double, repeated, tag = "4")]
    pub center: Vec<f64>,
    /// `length, width, height`, metres.
    #[prost(double, repeated, tag = "5")]
    pub size: Vec<f64>,
    /// Orientation quaternion `x, y, z, w` in the LiDAR frame.
    #[prost(double, repeated, tag = "6")]
    pub rotation: Vec<f64>,
    /// Heading about the LiDAR z axis, radians.
    #[prost(double, tag = "7")]
    pub yaw: f64,
    /// LiDAR returns on the target.
    #[prost(uint32, tag = "8")]
    pub lidar_points: u32,
    /// Range from the sensor to the box centre, metres.
    #[prost(double, tag = "9")]
    pub range_m: f64,
    /// Share of the target's part above the still water level that the waves hide from the LiDAR, 0..1 (0 over a
    /// flat sea).
    #[prost(double, tag = "10")]
    pub wave_occlusion: f64,
}

/// A bird's-eye-view box label (agent's BEV frame, metres and radians).
#[derive(Clone, PartialEq, Message)]
pub struct BevBox {
    /// Id of the labelled vessel.
    #[prost(string, tag = "1")]
    pub target_id: String,
    /// Centre x, metres.
    #[prost(double, tag = "2")]
    pub x: f64,
    /// Centre y, metres.
    #[prost(double, tag = "3")]
    pub y: f64,
    /// Box length, metres.
    #[prost(double, tag = "4")]
    pub length: f64,
    /// Box width, metres.
    #[prost(double, tag = "5")]
    pub width: f64,
    /// Heading, radians.
    #[prost(double, tag = "6")]
    pub yaw: f64,
}

/// A 2-D box label in one camera image (pixels, origin at the top-left corner).
#[derive(Clone, PartialEq, Message)]
pub struct Box2D {
    /// Id of the labelled vessel.
    #[prost(string, tag = "1")]
    pub target_id: String,
    /// Camera name.
    #[prost(string, tag = "2")]
    pub camera: String,
    /// Left edge, pixels.
    #[prost(double, tag = "3")]
    pub x_min: f64,
    /// Top edge, pixels.
    #[prost(double, tag = "4")]
    pub y_min: f64,
    /// Right edge, pixels.
    #[prost(double, tag = "5")]
    pub x_max: f64,
    /// Bottom edge, pixels.
    #[prost(double, tag = "6")]
    pub y_max: f64,
    /// Fraction of the projected box outside the image, 0..1.
    #[prost(double, tag = "7")]
    pub truncation: f64,
    /// Pixels of the target visible in the instance image.
    #[prost(uint32, tag = "8")]
    pub visible_pixels: u32,
    /// Pixels the clipped box touches, `(ceil x_max − floor x_min) · (ceil y_max − floor y_min)`: the window
    /// `visible_pixels` is counted in.
    #[prost(uint32, tag = "9")]
    pub box_pixels: u32,
    /// Fraction of the target's part above the still water level that is hidden (by other objects and by the
    /// waves), 0..1.
    #[prost(double, tag = "10")]
    pub occlusion: f64,
    /// Share of the target's part above the still water level that the waves hide from the camera, 0..1 (0 over
    /// a flat sea).
    #[prost(double, tag = "11")]
    pub wave_occlusion: f64,
}

/// Every label one agent produces at one frame.
#[derive(Clone, PartialEq, Message)]
pub struct AgentAnnotations {
    /// Frame index `k`.
    #[prost(uint64, tag = "1")]
    pub frame: u64,
    /// Simulation time, seconds.
    #[prost(double, tag = "2")]
    pub time_s: f64,
    /// Agent (USV) id.
    #[prost(string, tag = "3")]
    pub agent_id: String,
    /// 3-D boxes in the LiDAR frame.
    #[prost(message, repeated, tag = "4")]
    pub boxes_lidar: Vec<Box3D>,
    /// Bird's-eye-view boxes.
    #[prost(message, repeated, tag = "5")]
    pub boxes_bev: Vec<BevBox>,
    /// 2-D boxes, all cameras.
    #[prost(message, repeated, tag = "6")]
    pub boxes_camera: Vec<Box2D>,
}

/// Field kinds used by the own messages.
#[derive(Clone, Copy)]
enum Kind {
    Str,
    U32,
    U64,
    F64,
    Doubles,
    Msgs(&'static str),
}

/// `(field name, number, kind)` of every field of one message.
type Fields = &'static [(&'static str, i32, Kind)];

/// `(message name, fields)` for every own message, in declaration order.
const LAYOUT: &[(&str, Fields)] = &[
    (
        "VesselState",
        &[
            ("id", 1, Kind::Str),
            ("asset", 2, Kind::Str),
            ("role", 3, Kind::Str),
            ("semantic_class", 4, Kind::U32),
            ("instance_id", 5, Kind::U32),
            ("pose", 6, Kind::Doubles),
            ("velocity", 7, Kind::Doubles),
            ("box_center", 8, Kind::Doubles),
            ("box_size", 9, Kind::Doubles),
        ],
    ),
    ("WorldState", &[("frame", 1, Kind::U64), ("time_s", 2, Kind::F64), ("vessels", 3, Kind::Msgs("VesselState"))]),
    (
        "Box3D",
        &[
            ("target_id", 1, Kind::Str),
            ("instance_id", 2, Kind::U32),
            ("semantic_class", 3, Kind::U32),
            ("center", 4, Kind::Doubles),
            ("size", 5, Kind::Doubles),
            ("rotation", 6, Kind::Doubles),
            ("yaw", 7, Kind::F64),
            ("lidar_points", 8, Kind::U32),
            ("range_m", 9, Kind::F64),
            ("wave_occlusion", 10, Kind::F64),
        ],
    ),
    (
        "BevBox",
        &[
            ("target_id", 1, Kind::Str),
            ("x", 2, Kind::F64),
            ("y", 3, Kind::F64),
            ("length", 4, Kind::F64),
            ("width", 5, Kind::F64),
            ("yaw", 6, Kind::F64),
        ],
    ),
    (
        "Box2D",
        &[
            ("target_id", 1, Kind::Str),
            ("camera", 2, Kind::Str),
            ("x_min", 3, Kind::F64),
            ("y_min", 4, Kind::F64),
            ("x_max", 5, Kind::F64),
            ("y_max", 6, Kind::F64),
            ("truncation", 7, Kind::F64),
            ("visible_pixels", 8, Kind::U32),
            ("box_pixels", 9, Kind::U32),
            ("occlusion", 10, Kind::F64),
            ("wave_occlusion", 11, Kind::F64),
        ],
    ),
    (
        "AgentAnnotations",
        &[
            ("frame", 1, Kind::U64),
            ("time_s", 2, Kind::F64),
            ("agent_id", 3, Kind::Str),
            ("boxes_lidar", 4, Kind::Msgs("Box3D")),
            ("boxes_bev", 5, Kind::Msgs("BevBox")),
            ("boxes_camera", 6, Kind::Msgs("Box2D")),
        ],
    ),
];

fn field(name: &str, number: i32, kind: Kind) -> FieldDescriptorProto {
    let (ty, label, type_name) = match kind {
        Kind::Str => (Type::String, Label::Optional, None),
        Kind::U32 => (Type::Uint32, Label::Optional, None),
        Kind::U64 => (Type::Uint64, Label::Optional, None),
        Kind::F64 => (Type::Double, Label::Optional, None),
        Kind::Doubles => (Type::Double, Label::Repeated, None),
        Kind::Msgs(m) => (Type::Message, Label::Repeated, Some(format!(".{PACKAGE}.{m}"))),
    };
    FieldDescriptorProto {
        name: Some(name.to_string()),
        number: Some(number),
        label: Some(label as i32),
        r#type: Some(ty as i32),
        type_name,
        json_name: Some(json_name(name)),
        ..Default::default()
    }
}

/// protoc's lowerCamelCase JSON name.
fn json_name(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    let mut upper = false;
    for c in name.chars() {
        if c == '_' {
            upper = true;
        } else if upper {
            out.extend(c.to_uppercase());
            upper = false;
        } else {
            out.push(c);
        }
    }
    out
}

/// The descriptor set describing every own message (one file, package `mmusv`, proto3).
pub fn file_descriptor_set() -> FileDescriptorSet {
    let message_type = LAYOUT
        .iter()
        .map(|(name, fields)| DescriptorProto {
            name: Some((*name).to_string()),
            field: fields.iter().map(|&(n, num, k)| field(n, num, k)).collect(),
            ..Default::default()
        })
        .collect();
    FileDescriptorSet {
        file: vec![FileDescriptorProto {
            name: Some(PROTO_FILE.to_string()),
            package: Some(PACKAGE.to_string()),
            message_type,
            syntax: Some("proto3".to_string()),
            ..Default::default()
        }],
    }
}

/// The serialized descriptor set, built once.
pub fn descriptor_bytes() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| file_descriptor_set().encode_to_vec())
}

macro_rules! own_encode {
    ($ty:ident, $name:literal) => {
        impl Encode for $ty {
            type Error = prost::EncodeError;

            fn get_schema() -> Option<Schema> {
                Some(Schema::new(concat!("mmusv.", $name), "protobuf", descriptor_bytes()))
            }

            fn get_message_encoding() -> String {
                "protobuf".to_string()
            }

            fn encode(&self, buf: &mut impl prost::bytes::BufMut) -> Result<(), prost::EncodeError> {
                Message::encode(self, buf)
            }

            fn encoded_len(&self) -> Option<usize> {
                Some(Message::encoded_len(self))
            }
        }
    };
}

own_encode!(WorldState, "WorldState");
own_encode!(AgentAnnotations, "AgentAnnotations");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptor_decodes_and_names_every_field() {
        let set = FileDescriptorSet::decode(descriptor_bytes()).unwrap_or_default();
        assert_eq!(set.file.len(), 1);
        let file = &set.file[0];
        assert_eq!(file.package(), "mmusv");
        assert_eq!(file.syntax(), "proto3");
        let names: Vec<&str> = file.message_type.iter().map(|m| m.name()).collect();
        assert_eq!(names, ["VesselState", "WorldState", "Box3D", "BevBox", "Box2D", "AgentAnnotations"]);
        let vessel = &file.message_type[0];
        let fields: Vec<(&str, i32)> = vessel.field.iter().map(|f| (f.name(), f.number())).collect();
        assert_eq!(
            fields,
            [
                ("id", 1),
                ("asset", 2),
                ("role", 3),
                ("semantic_class", 4),
                ("instance_id", 5),
                ("pose", 6),
                ("velocity", 7),
                ("box_center", 8),
                ("box_size", 9)
            ]
        );
        assert_eq!(vessel.field[5].label(), Label::Repeated);
        assert_eq!(vessel.field[5].r#type(), Type::Double);
        let ann = &file.message_type[5];
        assert_eq!(ann.field[3].type_name(), ".mmusv.Box3D");
        assert_eq!(ann.field[3].label(), Label::Repeated);
        let box2d = &file.message_type[4];
        assert_eq!(box2d.field.len(), 11);
        assert_eq!(box2d.field[9].name(), "occlusion");
        assert_eq!(box2d.field[10].name(), "wave_occlusion");
        assert_eq!(box2d.field[7].json_name(), "visiblePixels");
    }

    /// Every field of every message, filled with a non-default value, round-trips through prost and lands
    /// on the tag the descriptor gives it (checked by walking the wire format).
    #[test]
    fn prost_tags_match_descriptor() {
        let v = VesselState {
            id: "a".into(),
            asset: "b".into(),
            role: "usv".into(),
            semantic_class: 11,
            instance_id: 3,
            pose: vec![1.0; 6],
            velocity: vec![2.0; 3],
            box_center: vec![3.0; 3],
            box_size: vec![4.0; 3],
        };
        let tags = wire_tags(&v.encode_to_vec());
        let want: Vec<(u32, u32)> = LAYOUT[0].1.iter().map(|&(_, n, k)| (n as u32, wire_type(k))).collect();
        assert_eq!(tags, want);
        let w = WorldState { frame: 7, time_s: 0.5, vessels: vec![v.clone()] };
        let back = WorldState::decode(w.encode_to_vec().as_slice()).unwrap_or_default();
        assert_eq!(back, w);
    }

    fn wire_type(k: Kind) -> u32 {
        match k {
            Kind::U32 | Kind::U64 => 0,
            Kind::F64 => 1,
            Kind::Str | Kind::Doubles | Kind::Msgs(_) => 2,
        }
    }

    /// `(field number, wire type)` of each top-level field in `buf`.
    fn wire_tags(mut buf: &[u8]) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        while !buf.is_empty() {
            let key = prost::encoding::decode_varint(&mut buf).unwrap_or(0) as u32;
            let (num, wt) = (key >> 3, key & 7);
            out.push((num, wt));
            let skip = match wt {
                0 => {
                    prost::encoding::decode_varint(&mut buf).unwrap_or(0);
                    0
                }
                1 => 8,
                2 => prost::encoding::decode_varint(&mut buf).unwrap_or(0) as usize,
                _ => buf.len(),
            };
            buf = &buf[skip..];
        }
        out
    }
}
