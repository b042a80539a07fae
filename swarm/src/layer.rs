//! A mission's layer of a picture: the marks `run.svg` draws over the trajectories, and that a
//! version-3 recording holds per tick (`recording::TickLayer`) for the viewer, which draws them
//! by kind without knowing the mission.

use serde::{Deserialize, Serialize};

/// One mark of a mission's layer, in arena coordinates (sizes in pixels).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Mark {
    /// A filled disc with an outline (`outline` None: none).
    Disc {
        at: [f64; 2],
        px: u32,
        fill: [u8; 3],
        outline: Option<[u8; 3]>,
    },
    /// A ring (circle outline) `width` pixels wide.
    Ring {
        at: [f64; 2],
        px: u32,
        colour: [u8; 3],
        width: u32,
    },
    /// A circle of `radius` arena units (a range, a body).
    Circle {
        at: [f64; 2],
        radius: f64,
        colour: [u8; 3],
    },
    /// A filled isosceles triangle `px` pixels long pointing along `heading` (rad, arena
    /// frame): a unicycle robot.
    Triangle {
        at: [f64; 2],
        heading: f64,
        px: u32,
        fill: [u8; 3],
    },
    /// A polyline.
    Path {
        points: Vec<[f64; 2]>,
        colour: [u8; 3],
    },
}
