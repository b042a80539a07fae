//! Foxglove's well-known message types, as serde structs that serialise to the JSON encoding
//! of Foxglove's published JSON schemas (`@foxglove/schemas` 2.1.0 on the npm registry; the
//! schemas themselves, MIT-licensed, are vendored beside this file in `schemas/` for the MCAP
//! schema records). Only the types the export writes; every field a schema requires is here.

use serde::Serialize;

/// The vendored schemas (name, JSON text), in the order of [`Schema`].
pub const SCENE_UPDATE: (&str, &str) = (
    "foxglove.SceneUpdate",
    include_str!("schemas/SceneUpdate.json"),
);
pub const FRAME_TRANSFORMS: (&str, &str) = (
    "foxglove.FrameTransforms",
    include_str!("schemas/FrameTransforms.json"),
);
pub const LOG: (&str, &str) = ("foxglove.Log", include_str!("schemas/Log.json"));

/// The frame everything is drawn in: the arena's, x right, y up, z out of the floor.
pub const WORLD_FRAME: &str = "world";

#[derive(Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Time {
    pub sec: u32,
    pub nsec: u32,
}

impl Time {
    pub fn from_ns(ns: u64) -> Time {
        Time {
            sec: (ns / 1_000_000_000) as u32,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// A duration (`lifetime` of an entity: zero is forever).
pub type Duration = Time;

#[derive(Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    /// A rotation of `yaw` rad about z.
    pub fn yaw(yaw: f64) -> Quaternion {
        let h = yaw / 2.0;
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: h.sin(),
            w: h.cos(),
        }
    }
}

#[derive(Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

impl Pose {
    /// At (x, y, z) on the floor, turned `yaw` rad about z.
    pub fn at(x: f64, y: f64, z: f64, yaw: f64) -> Pose {
        Pose {
            position: Vector3 { x, y, z },
            orientation: Quaternion::yaw(yaw),
        }
    }
}

/// RGBA, each 0..=1.
#[derive(Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Color {
    pub r: f64,
    pub g: f64,
    pub b: f64,
    pub a: f64,
}

impl Color {
    pub fn rgb(c: [u8; 3], a: f64) -> Color {
        Color {
            r: f64::from(c[0]) / 255.0,
            g: f64::from(c[1]) / 255.0,
            b: f64::from(c[2]) / 255.0,
            a,
        }
    }
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct KeyValuePair {
    pub key: String,
    pub value: String,
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct ArrowPrimitive {
    pub pose: Pose,
    pub shaft_length: f64,
    pub shaft_diameter: f64,
    pub head_length: f64,
    pub head_diameter: f64,
    pub color: Color,
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct CylinderPrimitive {
    pub pose: Pose,
    pub size: Vector3,
    pub bottom_scale: f64,
    pub top_scale: f64,
    pub color: Color,
}

/// `type`: 0 LINE_STRIP, 1 LINE_LOOP, 2 LINE_LIST.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct LinePrimitive {
    #[serde(rename = "type")]
    pub kind: u8,
    pub pose: Pose,
    pub thickness: f64,
    pub scale_invariant: bool,
    pub points: Vec<Vector3>,
    pub color: Color,
    pub colors: Vec<Color>,
    pub indices: Vec<u32>,
}

pub const LINE_STRIP: u8 = 0;
pub const LINE_LOOP: u8 = 1;

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct TriangleListPrimitive {
    pub pose: Pose,
    pub points: Vec<Vector3>,
    pub color: Color,
    pub colors: Vec<Color>,
    pub indices: Vec<u32>,
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct TextPrimitive {
    pub pose: Pose,
    pub billboard: bool,
    pub font_size: f64,
    pub scale_invariant: bool,
    pub color: Color,
    pub text: String,
}

/// The primitive lists of an entity this export never fills.
#[derive(Serialize, Clone, Debug, PartialEq, Default)]
pub struct Unused {}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct SceneEntity {
    pub timestamp: Time,
    pub frame_id: String,
    pub id: String,
    pub lifetime: Duration,
    pub frame_locked: bool,
    pub metadata: Vec<KeyValuePair>,
    pub arrows: Vec<ArrowPrimitive>,
    pub cubes: Vec<Unused>,
    pub spheres: Vec<Unused>,
    pub cylinders: Vec<CylinderPrimitive>,
    pub lines: Vec<LinePrimitive>,
    pub triangles: Vec<TriangleListPrimitive>,
    pub texts: Vec<TextPrimitive>,
    pub models: Vec<Unused>,
}

impl SceneEntity {
    /// An entity in the world frame, alive until the next update replaces it.
    pub fn new(timestamp: Time, id: String) -> SceneEntity {
        SceneEntity {
            timestamp,
            frame_id: WORLD_FRAME.to_string(),
            id,
            lifetime: Time { sec: 0, nsec: 0 },
            frame_locked: false,
            metadata: Vec::new(),
            arrows: Vec::new(),
            cubes: Vec::new(),
            spheres: Vec::new(),
            cylinders: Vec::new(),
            lines: Vec::new(),
            triangles: Vec::new(),
            texts: Vec::new(),
            models: Vec::new(),
        }
    }
    pub fn meta(mut self, key: &str, value: impl ToString) -> SceneEntity {
        self.metadata.push(KeyValuePair {
            key: key.to_string(),
            value: value.to_string(),
        });
        self
    }
}

/// `type`: 0 MATCHING_ID, 1 ALL.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct SceneEntityDeletion {
    pub timestamp: Time,
    #[serde(rename = "type")]
    pub kind: u8,
    pub id: String,
}

pub const DELETE_ALL: u8 = 1;

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct SceneUpdate {
    pub deletions: Vec<SceneEntityDeletion>,
    pub entities: Vec<SceneEntity>,
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct FrameTransform {
    pub timestamp: Time,
    pub parent_frame_id: String,
    pub child_frame_id: String,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct FrameTransforms {
    pub transforms: Vec<FrameTransform>,
}

/// `level`: 2 INFO, 3 WARNING, 4 ERROR.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct Log {
    pub timestamp: Time,
    pub level: u8,
    pub message: String,
    pub name: String,
    pub file: String,
    pub line: u32,
}

pub const LOG_INFO: u8 = 2;
pub const LOG_WARNING: u8 = 3;
pub const LOG_ERROR: u8 = 4;
