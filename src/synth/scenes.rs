//! The scenes: geometry, textures, object motions and the camera motion of each [`SceneKind`].
//! Units are metres in camera 1's frame (x right, y down, z forward): the floor is at positive y.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::SceneKind;
use super::raycast::{Object, Shape, Sheet};
use super::texture::{Pattern, Texture};
use crate::rng::Rng;

/// Objects of a scene and the camera motion (a static world point X is `R X + t` in camera 2).
pub struct Built {
    pub objects: Vec<Object>,
    pub camera_rotation: Matrix3<f64>,
    pub camera_translation: Vector3<f64>,
}

/// Builds the scene of `kind`.
pub fn build(kind: SceneKind) -> Built {
    match kind {
        SceneKind::StaticRoom => static_room(),
        SceneKind::Street => street(),
        SceneKind::Crowd => crowd(),
        SceneKind::Flag => flag(),
    }
}

const WOOD: [[f64; 3]; 3] = [[0.55, 0.36, 0.2], [0.75, 0.55, 0.32], [0.35, 0.22, 0.12]];
const PLASTER: [[f64; 3]; 3] = [[0.85, 0.82, 0.75], [0.6, 0.62, 0.66], [0.95, 0.9, 0.8]];
const BRICK: [[f64; 3]; 3] = [[0.62, 0.24, 0.16], [0.78, 0.42, 0.3], [0.55, 0.5, 0.45]];
const TEAL: [[f64; 3]; 3] = [[0.1, 0.45, 0.5], [0.85, 0.85, 0.7], [0.2, 0.25, 0.5]];
const ASPHALT: [[f64; 3]; 3] = [[0.3, 0.3, 0.32], [0.5, 0.5, 0.48], [0.2, 0.2, 0.22]];
const SKY: [[f64; 3]; 3] = [[0.45, 0.65, 0.92], [0.85, 0.9, 0.98], [0.6, 0.7, 0.85]];
const GLASS: [[f64; 3]; 3] = [[0.25, 0.35, 0.45], [0.8, 0.78, 0.7], [0.55, 0.6, 0.7]];
const FLAG: [[f64; 3]; 3] = [[0.9, 0.15, 0.15], [0.95, 0.95, 0.9], [0.1, 0.2, 0.7]];

/// Distinct vivid palettes for movers, picked by index.
fn mover_palette(i: usize) -> [[f64; 3]; 3] {
    const P: [[[f64; 3]; 3]; 6] = [
        [[0.9, 0.6, 0.1], [0.3, 0.2, 0.6], [0.95, 0.9, 0.6]],
        [[0.2, 0.7, 0.3], [0.9, 0.9, 0.2], [0.1, 0.3, 0.2]],
        [[0.8, 0.2, 0.5], [0.2, 0.6, 0.9], [0.9, 0.8, 0.9]],
        [[0.3, 0.3, 0.9], [0.95, 0.5, 0.3], [0.2, 0.8, 0.8]],
        [[0.6, 0.9, 0.9], [0.5, 0.1, 0.1], [0.9, 0.7, 0.2]],
        [[0.95, 0.95, 0.95], [0.1, 0.1, 0.1], [0.8, 0.3, 0.2]],
    ];
    P[i % P.len()]
}

/// A static rectangle `origin + s·u + t·v` in world coordinates.
fn wall(origin: [f64; 3], u: [f64; 3], v: [f64; 3], texture: Texture) -> Object {
    let id = Isometry3::identity();
    let shape = Shape::Quad {
        origin: Point3::from(origin),
        u: Vector3::from(u),
        v: Vector3::from(v),
    };
    Object::rigid(shape, id, id, texture, 0)
}

/// A box centred at `centre`, turned by `yaw` about the vertical axis, moved between the frames by
/// `shift` (metres) and turned about its own centre by the rotation vector `turn` (radians).
fn cuboid(
    centre: [f64; 3],
    half: [f64; 3],
    yaw: f64,
    motion: ([f64; 3], [f64; 3]),
    texture: Texture,
    group: u8,
) -> Object {
    let rotation = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), yaw);
    let pose0 = Isometry3::from_parts(Translation3::from(Vector3::from(centre)), rotation);
    let turn = UnitQuaternion::from_scaled_axis(Vector3::from(motion.1));
    let pose1 = Isometry3::from_parts(
        Translation3::from(Vector3::from(centre) + Vector3::from(motion.0)),
        turn * rotation,
    );
    Object::rigid(
        Shape::Cuboid {
            half: Vector3::from(half),
        },
        pose0,
        pose1,
        texture,
        group,
    )
}

/// Camera 2 with centre `centre` (world) turned by the rotation vector `turn` (radians):
/// a world point X is `R (X − C)` in camera 2, so R = rotation⁻¹ and t = −R C.
fn camera(centre: [f64; 3], turn: [f64; 3]) -> (Matrix3<f64>, Vector3<f64>) {
    let r = Rotation3::from_scaled_axis(Vector3::from(turn))
        .inverse()
        .into_inner();
    (r, -(r * Vector3::from(centre)))
}

const STILL: ([f64; 3], [f64; 3]) = ([0.0; 3], [0.0; 3]);

fn static_room() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    let objects = vec![
        wall(
            [-4.0, 1.5, 0.5],
            [8.0, 0.0, 0.0],
            [0.0, 0.0, 13.5],
            t(Pattern::Checker, 0.6, WOOD, 1),
        ),
        wall(
            [-4.0, -2.5, 0.5],
            [8.0, 0.0, 0.0],
            [0.0, 0.0, 13.5],
            t(Pattern::Noise, 0.7, PLASTER, 2),
        ),
        wall(
            [-4.0, -2.5, 0.5],
            [0.0, 0.0, 13.5],
            [0.0, 4.0, 0.0],
            t(Pattern::Bricks, 0.25, BRICK, 3),
        ),
        wall(
            [4.0, -2.5, 0.5],
            [0.0, 0.0, 13.5],
            [0.0, 4.0, 0.0],
            t(Pattern::Stripes, 0.5, TEAL, 4),
        ),
        wall(
            [-4.0, -2.5, 14.0],
            [8.0, 0.0, 0.0],
            [0.0, 4.0, 0.0],
            t(Pattern::Gradient, 0.4, PLASTER, 5),
        ),
        cuboid(
            [-1.6, 1.0, 5.0],
            [0.6, 0.5, 0.6],
            0.3,
            STILL,
            t(Pattern::Noise, 0.3, mover_palette(0), 6),
            0,
        ),
        cuboid(
            [1.5, 0.8, 7.0],
            [0.7, 0.7, 0.5],
            -0.4,
            STILL,
            t(Pattern::Checker, 0.2, mover_palette(1), 7),
            0,
        ),
        cuboid(
            [0.2, 0.3, 10.5],
            [0.8, 1.2, 0.4],
            0.1,
            STILL,
            t(Pattern::Stripes, 0.3, mover_palette(2), 8),
            0,
        ),
        cuboid(
            [-2.8, -0.6, 11.5],
            [0.5, 0.5, 0.5],
            0.7,
            STILL,
            t(Pattern::Bricks, 0.15, mover_palette(3), 9),
            0,
        ),
    ];
    let (camera_rotation, camera_translation) = camera([0.12, -0.04, 0.2], [-0.003, 0.006, 0.002]);
    Built {
        objects,
        camera_rotation,
        camera_translation,
    }
}

fn street() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    let objects = vec![
        wall(
            [-7.0, 1.6, 1.0],
            [14.0, 0.0, 0.0],
            [0.0, 0.0, 59.0],
            t(Pattern::Noise, 0.5, ASPHALT, 11),
        ),
        wall(
            [-7.0, -14.0, 1.0],
            [0.0, 0.0, 59.0],
            [0.0, 15.6, 0.0],
            t(Pattern::Bricks, 0.3, BRICK, 12),
        ),
        wall(
            [7.0, -14.0, 1.0],
            [0.0, 0.0, 59.0],
            [0.0, 15.6, 0.0],
            t(Pattern::Checker, 0.9, GLASS, 13),
        ),
        wall(
            [-7.0, -14.0, 60.0],
            [14.0, 0.0, 0.0],
            [0.0, 15.6, 0.0],
            t(Pattern::Noise, 2.0, SKY, 14),
        ),
        wall(
            [-7.0, -14.0, 1.0],
            [14.0, 0.0, 0.0],
            [0.0, 0.0, 59.0],
            t(Pattern::Noise, 3.0, SKY, 15),
        ),
        cuboid(
            [-2.6, 0.9, 11.0],
            [0.9, 0.7, 2.1],
            0.0,
            ([0.0, 0.0, 0.7], [0.0; 3]),
            t(Pattern::Stripes, 0.35, mover_palette(0), 16),
            1,
        ),
        cuboid(
            [2.7, 0.85, 17.0],
            [0.95, 0.75, 2.2],
            0.05,
            ([-0.15, 0.0, -0.9], [0.0, 0.045, 0.0]),
            t(Pattern::Checker, 0.3, mover_palette(2), 17),
            2,
        ),
    ];
    let (camera_rotation, camera_translation) = camera([0.05, 0.0, 0.45], [0.0, 0.006, 0.0]);
    Built {
        objects,
        camera_rotation,
        camera_translation,
    }
}

/// People (tall boxes) standing on the floor in three staggered rows, each walking its own way:
/// a shift along the floor and a turn about the vertical axis, so every box keeps its feet on
/// the floor in both frames. (Boxes floating in the air would make each mover's scale
/// unobservable from two views; standing on the floor, their contact with it fixes it.)
fn crowd() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    const FLOOR_Y: f64 = 1.2;
    let mut objects = vec![
        wall(
            [-12.0, -6.0, 14.0],
            [24.0, 0.0, 0.0],
            [0.0, 6.0 + FLOOR_Y, 0.0],
            t(Pattern::Noise, 0.8, PLASTER, 21),
        ),
        wall(
            [-12.0, FLOOR_Y, 1.0],
            [24.0, 0.0, 0.0],
            [0.0, 0.0, 13.0],
            t(Pattern::Checker, 0.7, WOOD, 22),
        ),
    ];
    let mut rng = Rng::new(2017);
    let patterns = [
        Pattern::Noise,
        Pattern::Bricks,
        Pattern::Stripes,
        Pattern::Checker,
        Pattern::Gradient,
    ];
    // (depth, first x, spacing, people) per row: rows further back are wider and offset by half
    // a spacing, so feet stay visible between the people in front.
    let rows = [
        (6.0, -3.0, 1.2, 6),
        (7.8, -3.9, 1.3, 7),
        (9.8, -4.9, 1.4, 8),
    ];
    let mut i = 0;
    for &(depth, first, spacing, people) in &rows {
        for col in 0..people {
            let mut jitter = |a: f64| (rng.uniform() - 0.5) * 2.0 * a;
            let half = [0.42 + jitter(0.07), 0.87 + jitter(0.08), 0.3 + jitter(0.05)];
            let centre = [
                first + spacing * col as f64 + jitter(0.15),
                FLOOR_Y - half[1],
                depth + jitter(0.4),
            ];
            let shift = [jitter(0.12), 0.0, jitter(0.12)];
            let turn = [0.0, jitter(0.06), 0.0];
            let yaw = jitter(0.6);
            let texture = t(
                patterns[i % patterns.len()],
                0.2 + 0.1 * (i % 3) as f64,
                mover_palette(i),
                30 + i as u32,
            );
            objects.push(cuboid(
                centre,
                half,
                yaw,
                (shift, turn),
                texture,
                i as u8 + 1,
            ));
            i += 1;
        }
    }
    let (camera_rotation, camera_translation) = camera([0.06, 0.0, 0.1], [0.0, 0.006, 0.0]);
    Built {
        objects,
        camera_rotation,
        camera_translation,
    }
}

fn flag() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    let (cols, rows, width, height) = (57, 37, 2.8, 1.8);
    let sheet = Sheet::new(
        cols,
        rows,
        |i, j| {
            [
                width * i as f64 / (cols - 1) as f64,
                height * j as f64 / (rows - 1) as f64,
            ]
        },
        |i, j, time| {
            let s = width * i as f64 / (cols - 1) as f64;
            let h = height * j as f64 / (rows - 1) as f64;
            let phase = [0.0, 0.7][time];
            let amplitude = 0.45 * s / width;
            let wave = (std::f64::consts::TAU * s / 1.6 - phase + 0.4 * h).sin();
            Point3::new(
                -1.55 + s,
                -1.2 + h + 0.05 * wave * s / width,
                5.0 + amplitude * wave,
            )
        },
    );
    let id = Isometry3::identity();
    let objects = vec![
        wall(
            [-8.0, -4.0, 9.0],
            [16.0, 0.0, 0.0],
            [0.0, 5.4, 0.0],
            t(Pattern::Bricks, 0.25, BRICK, 41),
        ),
        wall(
            [-8.0, 1.4, 1.0],
            [16.0, 0.0, 0.0],
            [0.0, 0.0, 8.0],
            t(Pattern::Checker, 0.5, WOOD, 42),
        ),
        cuboid(
            [-1.62, 0.1, 5.0],
            [0.06, 1.4, 0.06],
            0.0,
            STILL,
            t(Pattern::Noise, 0.1, PLASTER, 43),
            0,
        ),
        Object::rigid(
            Shape::Sheet(sheet),
            id,
            id,
            t(Pattern::Stripes, 0.45, FLAG, 44),
            1,
        ),
    ];
    let (camera_rotation, camera_translation) = camera([0.12, -0.02, 0.05], [0.0, -0.009, 0.0]);
    Built {
        objects,
        camera_rotation,
        camera_translation,
    }
}
