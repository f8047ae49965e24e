//! Synthetic dynamic scenes with exact ground truth, rendered by a small ray-caster: both frames,
//! the exact z-depth of frame 1, the exact flow 1→2 (the same surface point projected in frame 2),
//! masks of moving and still-visible pixels, motion groups, intrinsics and the camera motion.
//! Deterministic: each scene is fixed, textures are hash-based.
//!
//! Conventions: world frame = camera 1 (x right, y down, z forward), metres; pixel centres at
//! integers; camera 2 sees a static world point X as `R X + t` ([`SynthScene::camera_motion`]).

mod raycast;
mod scenes;
mod texture;

use nalgebra::{Matrix3, Point3, Vector3};

use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::flow::FlowField;
use crate::grid::Grid;
use crate::image::Frame;
use raycast::{Object, Ray, cast};

/// The scenes the generator knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// A textured room with furniture; only the camera moves.
    StaticRoom,
    /// A street: the camera drives forward, two cars move on their own.
    Street,
    /// A crowd: many people (tall boxes) walking on a floor, each its own way, covering most of
    /// the view.
    Crowd,
    /// A waving flag (a deforming sheet) in front of a static wall.
    Flag,
    /// A big creature close to the camera (a tube mesh that bends and swells, its feet on the
    /// floor) in front of four walkers (boxes on the floor, each shifting and turning its own
    /// way), while the camera pans (turns, and moves a little sideways).
    Creature,
    /// A road seen from a car driving forward along it: cars in both directions at several
    /// distances and speeds (one pulling away, one we close in on, a truck at our speed, two
    /// oncoming), buildings, a wall and lamp posts by the road.
    Road,
    /// Boxes resting on a table in a room while the camera orbits about the table (turning
    /// and moving, so there is parallax); one flat box slides across the table top.
    Table,
}

impl SceneKind {
    /// Every scene, in a fixed order.
    pub const ALL: [SceneKind; 7] = [
        SceneKind::StaticRoom,
        SceneKind::Street,
        SceneKind::Crowd,
        SceneKind::Flag,
        SceneKind::Creature,
        SceneKind::Road,
        SceneKind::Table,
    ];

    /// The scene's name as used on the command line and as its case folder.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::StaticRoom => "static-room",
            SceneKind::Street => "street",
            SceneKind::Crowd => "crowd",
            SceneKind::Flag => "flag",
            SceneKind::Creature => "creature",
            SceneKind::Road => "road",
            SceneKind::Table => "table",
        }
    }

    /// The scene called `name`.
    pub fn from_name(name: &str) -> Result<Self> {
        SceneKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = SceneKind::ALL.iter().map(|k| k.name()).collect();
                Error::InvalidParameter(format!(
                    "unknown scene {name:?}; choose one of {}",
                    names.join(", ")
                ))
            })
    }
}

/// A rigid motion `X' = r X + t` (`r` row-major rotation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidMotion {
    pub r: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl RigidMotion {
    /// Applies the motion to a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.r;
        [0, 1, 2].map(|i| r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + self.t[i])
    }
}

/// A rendered scene with exact ground truth.
#[derive(Clone, Debug)]
pub struct SynthScene {
    pub frame1: Frame,
    pub frame2: Frame,
    /// Exact z-depth of frame 1 at pixel centres (camera-1 frame); NaN where no surface.
    pub depth1: Grid<f32>,
    /// Exact flow 1→2 of every pixel with a depth, occluded ones included.
    pub flow12: FlowField,
    /// Exact z-depth in camera 2 of frame 1's surface point at each frame-1 pixel (camera-2
    /// frame; occluded points included); NaN where no surface. With `depth1` and `flow12` it
    /// gives every pixel's 3D point at both times: the scene flow.
    pub depth12: Grid<f32>,
    /// True where the surface moves in the world (rigid mover or deforming sheet).
    pub moving1: Grid<bool>,
    /// Motion group: 0 = static world, 1.. = each independent mover or sheet.
    pub group1: Grid<u8>,
    /// True where frame 1's surface point is inside frame 2 and not occluded there.
    pub visible2: Grid<bool>,
    /// Intrinsics of both frames.
    pub intrinsics: Intrinsics,
    /// Camera 2 pose relative to camera 1: a static point X (camera-1 frame) is `R X + t` in
    /// camera 2.
    pub camera_motion: RigidMotion,
}

/// Largest side accepted by [`render`].
pub const MAX_SIDE: usize = 8192;

/// Renders `kind` at `width × height` pixels. Intrinsics follow the size: fx = fy = 0.8·W,
/// principal point at the centre.
pub fn render(kind: SceneKind, width: usize, height: usize) -> Result<SynthScene> {
    if width < 16 || height < 16 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::InvalidParameter(format!(
            "synthetic scenes are rendered between 16 and {MAX_SIDE} pixels a side, got {width}×{height}"
        )));
    }
    let intrinsics = Intrinsics {
        fx: 0.8 * width as f64,
        fy: 0.8 * width as f64,
        cx: width as f64 / 2.0 - 0.5,
        cy: height as f64 / 2.0 - 0.5,
    };
    let scene = scenes::build(kind);
    let cam2 = View::new(intrinsics, scene.camera_rotation, scene.camera_translation);
    let cam1 = View::new(intrinsics, Matrix3::identity(), Vector3::zeros());
    let objects = &scene.objects;

    let frame1 = render_colour(objects, &cam1, 0, width, height);
    let frame2 = render_colour(objects, &cam2, 1, width, height);
    let mut depth1 = Grid::filled(width, height, f32::NAN);
    let mut flow12 = Grid::filled(width, height, [f32::NAN; 2]);
    let mut depth12 = Grid::filled(width, height, f32::NAN);
    let mut moving1 = Grid::filled(width, height, false);
    let mut group1 = Grid::filled(width, height, 0u8);
    let mut visible2 = Grid::filled(width, height, false);
    for y in 0..height {
        for x in 0..width {
            let Some(hit) = cast(objects, &cam1.ray(x as f64, y as f64), 0) else {
                continue;
            };
            let object = &objects[hit.object];
            let p2 = cam2.to_camera(&object.world_point(&hit.anchor, 1));
            let [u2, v2] = intrinsics.project([p2.x, p2.y, p2.z]);
            *depth1.get_mut(x, y) = hit.lambda as f32;
            *flow12.get_mut(x, y) = [(u2 - x as f64) as f32, (v2 - y as f64) as f32];
            *depth12.get_mut(x, y) = p2.z as f32;
            *moving1.get_mut(x, y) = object.group != 0;
            *group1.get_mut(x, y) = object.group;
            *visible2.get_mut(x, y) =
                p2.z > 0.0 && cam2.sees(objects, hit.object, u2, v2, p2.z, width, height);
        }
    }
    let r = scene.camera_rotation;
    let t = scene.camera_translation;
    Ok(SynthScene {
        frame1,
        frame2,
        depth1,
        flow12,
        depth12,
        moving1,
        group1,
        visible2,
        intrinsics,
        camera_motion: RigidMotion {
            r: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
            t: [t.x, t.y, t.z],
        },
    })
}

/// A pinhole camera at some pose: a world point X is `r X + t` in its frame.
struct View {
    k: Intrinsics,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

impl View {
    fn new(k: Intrinsics, r: Matrix3<f64>, t: Vector3<f64>) -> Self {
        View { k, r, t }
    }

    /// World-frame ray through pixel (u, v) whose parameter is the camera-frame depth.
    fn ray(&self, u: f64, v: f64) -> Ray {
        let d = Vector3::from(self.k.ray(u, v));
        let rt = self.r.transpose();
        Ray {
            origin: Point3::from(-(rt * self.t)),
            dir: rt * d,
        }
    }

    fn to_camera(&self, p: &Point3<f64>) -> Vector3<f64> {
        self.r * p.coords + self.t
    }

    /// True when (u, v) lies in the image and the first surface there is `object` at depth `z`.
    #[allow(clippy::too_many_arguments)]
    fn sees(
        &self,
        objects: &[Object],
        object: usize,
        u: f64,
        v: f64,
        z: f64,
        width: usize,
        height: usize,
    ) -> bool {
        let inside = u >= -0.5 && v >= -0.5 && u <= width as f64 - 0.5 && v <= height as f64 - 0.5;
        inside
            && cast(objects, &self.ray(u, v), 1)
                .is_some_and(|h| h.object == object && (h.lambda - z).abs() <= 1e-6 * z.max(1.0))
    }
}

/// Supersampling grid per pixel side (3 × 3 rays per pixel).
const SUPERSAMPLE: usize = 3;

/// Renders the colour frame seen by `view` at `time`, anti-aliased by supersampling.
fn render_colour(
    objects: &[Object],
    view: &View,
    time: usize,
    width: usize,
    height: usize,
) -> Frame {
    let n = SUPERSAMPLE as f64;
    Grid::from_fn(width, height, |x, y| {
        let mut sum = [0.0f64; 3];
        for sy in 0..SUPERSAMPLE {
            for sx in 0..SUPERSAMPLE {
                let u = x as f64 + (sx as f64 + 0.5) / n - 0.5;
                let v = y as f64 + (sy as f64 + 0.5) / n - 0.5;
                if let Some(hit) = cast(objects, &view.ray(u, v), time) {
                    let c = objects[hit.object].colour(&hit.anchor);
                    sum.iter_mut().zip(c).for_each(|(s, c)| *s += c);
                }
            }
        }
        sum.map(|s| (s / (n * n) * 255.0).round().clamp(0.0, 255.0) as u8)
    })
}
