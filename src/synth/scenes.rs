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
        SceneKind::Creature => creature(),
        SceneKind::Road => road(),
        SceneKind::Table => table(),
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
const TIGER: [[f64; 3]; 3] = [[0.92, 0.5, 0.12], [0.12, 0.08, 0.06], [0.95, 0.88, 0.7]];
const GRASS: [[f64; 3]; 3] = [[0.25, 0.45, 0.15], [0.45, 0.55, 0.25], [0.35, 0.3, 0.18]];
const CONCRETE: [[f64; 3]; 3] = [[0.62, 0.6, 0.56], [0.75, 0.74, 0.7], [0.45, 0.44, 0.42]];

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
/// No motion of a box standing on a floor (see `standing`).
const STAY: ([f64; 2], f64) = ([0.0; 2], 0.0);

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

/// A stage: a frame whose y axis points along gravity (floors are planes y = const), with its
/// origin at camera 1's centre, seen by camera 1 looking down by `pitch` radians. Scenes built on
/// a stage are moved into camera 1's frame (the world frame) by this isometry.
fn stage(pitch: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * pitch)
}

/// Objects built in the stage frame `g`, moved into camera 1's frame.
fn staged(g: &Isometry3<f64>, objects: Vec<Object>) -> Vec<Object> {
    objects
        .into_iter()
        .map(|o| match &o.shape {
            Shape::Sheet(sheet) => Object::rigid(
                Shape::Sheet(sheet.moved(g)),
                o.pose[0],
                o.pose[1],
                o.texture,
                o.group,
            ),
            _ => Object::rigid(o.shape, g * o.pose[0], g * o.pose[1], o.texture, o.group),
        })
        .collect()
}

/// [`camera`] with its centre and turn given in the stage frame `g`.
fn staged_camera(
    g: &Isometry3<f64>,
    centre: [f64; 3],
    turn: [f64; 3],
) -> (Matrix3<f64>, Vector3<f64>) {
    let c = g.rotation * Vector3::from(centre);
    let t = g.rotation * Vector3::from(turn);
    camera([c.x, c.y, c.z], [t.x, t.y, t.z])
}

/// Camera 2 orbiting by `angle` radians about the vertical axis (stage y) through `pivot`
/// (stage frame): its centre turns about the axis and its orientation turns with it, so a
/// point on the axis stays where it was in the image.
fn orbit(g: &Isometry3<f64>, pivot: [f64; 3], angle: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let q = Rotation3::from_scaled_axis(Vector3::y() * angle);
    let p = Vector3::from(pivot);
    let c = p - q * p;
    staged_camera(g, [c.x, c.y, c.z], [0.0, angle, 0.0])
}

/// A box standing at `at` (x, z) on the floor plane y = `floor` (stage frame): its centre is
/// `half[1]` above the floor, and it moves by `motion`, a shift (x, z) along the floor and a turn
/// about the vertical (radians), so it stands on the floor in both frames.
fn standing(
    floor: f64,
    at: [f64; 2],
    half: [f64; 3],
    yaw: f64,
    motion: ([f64; 2], f64),
    texture: Texture,
    group: u8,
) -> Object {
    let (shift, turn) = motion;
    cuboid(
        [at[0], floor - half[1], at[1]],
        half,
        yaw,
        ([shift[0], 0.0, shift[1]], [0.0, turn, 0.0]),
        texture,
        group,
    )
}

/// A car on the road plane y = `road`: a body and a cabin (two boxes of one rigid motion, a
/// pure shift `dz` along the road), its bottom on the road. `at` is its centre on the road
/// (x, z), `size` its width, length and body height.
fn car(road: f64, at: [f64; 2], size: [f64; 3], dz: f64, palette: usize, group: u8) -> [Object; 2] {
    let t = |p, s, seed| Texture::new(p, s, mover_palette(palette), seed);
    let [w, l, h] = size;
    let seed = 60 + 2 * group as u32;
    [
        cuboid(
            [at[0], road - h / 2.0, at[1]],
            [w / 2.0, h / 2.0, l / 2.0],
            0.0,
            ([0.0, 0.0, dz], [0.0; 3]),
            t(Pattern::Stripes, 0.3, seed),
            group,
        ),
        cuboid(
            [at[0], road - h - 0.3, at[1] + 0.1 * l],
            [0.45 * w, 0.3, 0.28 * l],
            0.0,
            ([0.0, 0.0, dz], [0.0; 3]),
            t(Pattern::Checker, 0.2, seed + 1),
            group,
        ),
    ]
}

/// Camera 1's pitch (radians) and the floor's height (stage y, metres) of [`creature`].
const CREATURE_PITCH: f64 = 0.22;
const CREATURE_FLOOR: f64 = 1.7;
/// Camera 1's pitch and the road's height of [`road`].
const ROAD_PITCH: f64 = 0.03;
const ROAD_Y: f64 = 1.35;
/// The table top's height and its centre (x, z) in [`table`]'s stage.
const TABLE_TOP: f64 = 0.84;
const TABLE_CENTRE: [f64; 2] = [0.0, 1.75];

/// Camera 1 of [`table`] looks down at the table's centre.
fn table_pitch() -> f64 {
    (TABLE_TOP / TABLE_CENTRE[1]).atan()
}

/// A big creature standing close to the camera, bending (a tube of 48 × 40 vertices around a
/// spine that curls further to the right and towards the camera between the frames, and
/// breathes), in front of four walkers (boxes on the floor, each with its own shift and turn).
/// The camera pans: it turns right and moves a little sideways. The creature's feet stay on the
/// floor: its base ring is the same in both frames.
fn creature() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    const FLOOR_Y: f64 = CREATURE_FLOOR;
    let g = stage(CREATURE_PITCH);
    let mut objects = vec![
        wall(
            [-10.0, FLOOR_Y, 0.5],
            [20.0, 0.0, 0.0],
            [0.0, 0.0, 11.5],
            t(Pattern::Checker, 0.6, WOOD, 71),
        ),
        wall(
            [-10.0, FLOOR_Y - 5.0, 12.0],
            [20.0, 0.0, 0.0],
            [0.0, 5.0, 0.0],
            t(Pattern::Bricks, 0.3, BRICK, 72),
        ),
        Object::rigid(
            Shape::Sheet(creature_sheet(FLOOR_Y)),
            Isometry3::identity(),
            Isometry3::identity(),
            t(Pattern::Stripes, 0.22, TIGER, 73),
            1,
        ),
    ];
    // (x, z, half extents, yaw, shift, turn) of each walker.
    let walkers = [
        ([1.2, 6.5], [0.3, 0.85, 0.22], 0.3, [0.1, -0.06], 0.05),
        ([2.7, 8.0], [0.32, 0.9, 0.25], -0.5, [-0.12, 0.04], -0.04),
        ([-2.9, 7.2], [0.28, 0.8, 0.2], 0.8, [0.08, 0.1], 0.06),
        ([0.1, 9.5], [0.35, 0.95, 0.25], -0.2, [0.14, 0.0], -0.05),
    ];
    let patterns = [
        Pattern::Noise,
        Pattern::Checker,
        Pattern::Bricks,
        Pattern::Gradient,
    ];
    for (i, (at, half, yaw, shift, turn)) in walkers.into_iter().enumerate() {
        let texture = t(patterns[i], 0.2, mover_palette(i + 1), 74 + i as u32);
        objects.push(standing(
            FLOOR_Y,
            at,
            half,
            yaw,
            (shift, turn),
            texture,
            i as u8 + 2,
        ));
    }
    let (camera_rotation, camera_translation) =
        staged_camera(&g, [0.05, 0.0, 0.02], [0.0, 0.012, 0.0]);
    Built {
        objects: staged(&g, objects),
        camera_rotation,
        camera_translation,
    }
}

/// The creature of [`creature`] in the stage frame: a closed tube around a circular-arc spine
/// rising from its base on the floor, with a body, a neck and a rounded head; between the
/// frames the arc bends further (0.5 → 0.6 rad) and the body swells by up to 3 % towards the
/// head. The base ring lies on the floor, the same in both frames.
fn creature_sheet(floor: f64) -> Sheet {
    let (cols, rows) = (48, 40);
    const LENGTH: f64 = 1.8;
    let base = Vector3::new(-1.0, floor, 4.0);
    let up = Vector3::new(0.0, -1.0, 0.0);
    let bend = Vector3::new(1.0, 0.0, -0.45).normalize();
    let side = up.cross(&bend);
    // The texture's seam (angle 0 around the tube) faces away from the camera.
    let away = Vector3::new(base.x, 0.0, base.z).normalize();
    let seam = away.dot(&side).atan2(away.dot(&bend));
    // Radius along the spine (fraction of its length): hips, belly, chest, neck, head.
    let radius = |u: f64| -> f64 {
        const KNOTS: [(f64, f64); 5] = [
            (0.0, 0.68),
            (0.35, 0.89),
            (0.62, 0.81),
            (0.78, 0.46),
            (0.86, 0.55),
        ];
        if u >= KNOTS[4].0 {
            let (u0, r0) = KNOTS[4];
            return r0 * (1.0 - ((u - u0) / (1.0 - u0)).powi(2)).max(0.0).sqrt();
        }
        let k = KNOTS.iter().rposition(|&(a, _)| a <= u).unwrap_or(0);
        let ((a, ra), (b, rb)) = (KNOTS[k], KNOTS[k + 1]);
        ra + (rb - ra) * (u - a) / (b - a)
    };
    let angle = |i: usize| seam + std::f64::consts::TAU * i as f64 / (cols - 1) as f64;
    Sheet::new(
        cols,
        rows,
        |i, j| {
            [
                0.45 * (angle(i) - seam),
                LENGTH * j as f64 / (rows - 1) as f64,
            ]
        },
        |i, j, time| {
            let u = j as f64 / (rows - 1) as f64;
            let arc = [0.5, 0.6][time];
            let swell = 1.0 + [0.0, 0.03][time] * u;
            let k = arc / LENGTH;
            let phi = arc * u;
            let centre = base + up * (phi.sin() / k) + bend * ((1.0 - phi.cos()) / k);
            let normal = bend * phi.cos() - up * phi.sin();
            let r = radius(u) * swell;
            let a = angle(i);
            Point3::from(centre + normal * (r * a.cos()) + side * (0.85 * r * a.sin()))
        },
    )
}

/// A road seen from a car driving forward along it (0.28 m between the frames): five cars on
/// the road, a near one in the right lane pulling away, one ahead in our lane that we close
/// in on, a truck far ahead at our speed, and two oncoming in the left lane; buildings, a wall
/// and lamp posts by the road, hills and sky at the end.
fn road() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    const FORWARD: f64 = 0.28;
    let g = stage(ROAD_PITCH);
    let mut objects = vec![
        wall(
            [-5.6, ROAD_Y, 0.5],
            [10.8, 0.0, 0.0],
            [0.0, 0.0, 71.5],
            t(Pattern::Noise, 0.5, ASPHALT, 81),
        ),
        wall(
            [-60.0, ROAD_Y, 0.5],
            [54.4, 0.0, 0.0],
            [0.0, 0.0, 71.5],
            t(Pattern::Noise, 0.6, GRASS, 82),
        ),
        wall(
            [5.2, ROAD_Y, 0.5],
            [54.8, 0.0, 0.0],
            [0.0, 0.0, 71.5],
            t(Pattern::Checker, 0.5, CONCRETE, 83),
        ),
        wall(
            [-60.0, ROAD_Y - 4.0, 70.0],
            [120.0, 0.0, 0.0],
            [0.0, 4.0, 0.0],
            t(Pattern::Noise, 1.5, GRASS, 84),
        ),
        wall(
            [-60.0, ROAD_Y - 30.0, 72.0],
            [120.0, 0.0, 0.0],
            [0.0, 30.0, 0.0],
            t(Pattern::Noise, 3.0, SKY, 85),
        ),
        wall(
            [7.0, ROAD_Y - 1.1, 2.0],
            [0.0, 0.0, 40.0],
            [0.0, 1.1, 0.0],
            t(Pattern::Bricks, 0.25, BRICK, 86),
        ),
    ];
    // Buildings: (x of the side facing the road, z from, z to, depth, height), static.
    let buildings: [(f64, f64, f64, f64, f64); 6] = [
        (-8.0, 6.0, 19.0, 8.0, 9.0),
        (-9.5, 22.0, 31.0, 6.0, 14.0),
        (-8.0, 34.0, 52.0, 10.0, 7.0),
        (10.0, 10.0, 24.0, 8.0, 11.0),
        (9.0, 27.0, 45.0, 7.0, 16.0),
        (11.0, 48.0, 62.0, 9.0, 8.0),
    ];
    let palettes = [GLASS, PLASTER, BRICK, CONCRETE, GLASS, TEAL];
    let patterns = [
        Pattern::Checker,
        Pattern::Noise,
        Pattern::Bricks,
        Pattern::Stripes,
    ];
    for (i, &(face, z0, z1, depth, height)) in buildings.iter().enumerate() {
        let x = face + face.signum() * depth / 2.0;
        objects.push(cuboid(
            [x, ROAD_Y - height / 2.0, (z0 + z1) / 2.0],
            [depth / 2.0, height / 2.0, (z1 - z0) / 2.0],
            0.0,
            STILL,
            t(patterns[i % 4], 0.8, palettes[i], 90 + i as u32),
            0,
        ));
    }
    for (i, z) in [9.0, 21.0, 33.0, 45.0].into_iter().enumerate() {
        objects.push(cuboid(
            [6.0, ROAD_Y - 3.0, z],
            [0.08, 3.0, 0.08],
            0.0,
            STILL,
            t(Pattern::Noise, 0.2, CONCRETE, 100 + i as u32),
            0,
        ));
    }
    // (lane x, z, width, length, body height, shift along z, palette) of each car.
    let cars = [
        ([3.3, 10.5], [1.8, 4.3, 0.8], FORWARD + 0.14, 0),
        ([0.0, 17.0], [1.8, 4.5, 0.85], FORWARD - 0.1, 1),
        ([3.3, 36.0], [2.5, 9.0, 2.6], FORWARD, 2),
        ([-3.4, 23.0], [1.8, 4.4, 0.8], -0.6, 3),
        ([-3.4, 48.0], [1.9, 4.6, 0.9], -0.55, 4),
    ];
    for (i, (at, size, dz, palette)) in cars.into_iter().enumerate() {
        objects.extend(car(ROAD_Y, at, size, dz, palette, i as u8 + 1));
    }
    let (camera_rotation, camera_translation) =
        staged_camera(&g, [0.0, 0.0, FORWARD], [0.0, -0.003, 0.0]);
    Built {
        objects: staged(&g, objects),
        camera_rotation,
        camera_translation,
    }
}

/// A table in a room, seen from above at 1.75 m while the camera orbits 2° about the vertical
/// through the table's centre (turning and moving sideways, so depth gives parallax): five
/// boxes of several sizes rest on the table top; one of them (a flat box) slides 5 cm across
/// it and turns a little.
fn table() -> Built {
    let t = |p, s, c, seed| Texture::new(p, s, c, seed);
    const FLOOR_Y: f64 = 1.6;
    const TOP_Y: f64 = TABLE_TOP;
    const CENTRE: [f64; 2] = TABLE_CENTRE;
    let g = stage(table_pitch());
    let mut objects = vec![
        wall(
            [-4.0, FLOOR_Y, -1.0],
            [8.0, 0.0, 0.0],
            [0.0, 0.0, 6.0],
            t(Pattern::Checker, 0.45, WOOD, 111),
        ),
        wall(
            [-4.0, FLOOR_Y - 2.8, 5.0],
            [8.0, 0.0, 0.0],
            [0.0, 2.8, 0.0],
            t(Pattern::Noise, 0.6, PLASTER, 112),
        ),
        wall(
            [-4.0, FLOOR_Y - 2.8, -1.0],
            [0.0, 0.0, 6.0],
            [0.0, 2.8, 0.0],
            t(Pattern::Stripes, 0.4, TEAL, 113),
        ),
        wall(
            [4.0, FLOOR_Y - 2.8, -1.0],
            [0.0, 0.0, 6.0],
            [0.0, 2.8, 0.0],
            t(Pattern::Bricks, 0.2, BRICK, 114),
        ),
        cuboid(
            [CENTRE[0], TOP_Y + 0.025, CENTRE[1]],
            [0.85, 0.025, 0.55],
            0.0,
            STILL,
            t(Pattern::Gradient, 0.3, WOOD, 115),
            0,
        ),
    ];
    let leg = (FLOOR_Y - TOP_Y - 0.05) / 2.0;
    for (i, (dx, dz)) in [(-0.75, -0.45), (0.75, -0.45), (-0.75, 0.45), (0.75, 0.45)]
        .into_iter()
        .enumerate()
    {
        objects.push(standing(
            FLOOR_Y,
            [CENTRE[0] + dx, CENTRE[1] + dz],
            [0.04, leg, 0.04],
            0.0,
            STAY,
            t(Pattern::Noise, 0.1, WOOD, 116 + i as u32),
            0,
        ));
    }
    // (x, z offset from the table's centre, half extents, yaw, shift, turn, group) per box.
    let boxes = [
        ([-0.45, -0.15], [0.15, 0.1, 0.12], 0.3, [0.0; 2], 0.0, 0),
        ([0.1, 0.22], [0.08, 0.22, 0.08], -0.2, [0.0; 2], 0.0, 0),
        (
            [0.4, -0.25],
            [0.22, 0.04, 0.16],
            0.15,
            [0.05, -0.02],
            0.08,
            1,
        ),
        ([-0.12, -0.3], [0.1, 0.1, 0.1], 0.6, [0.0; 2], 0.0, 0),
        ([0.55, 0.28], [0.12, 0.15, 0.18], -0.4, [0.0; 2], 0.0, 0),
        ([-0.5, 0.3], [0.2, 0.06, 0.14], 0.9, [0.0; 2], 0.0, 0),
    ];
    let patterns = [
        Pattern::Noise,
        Pattern::Stripes,
        Pattern::Checker,
        Pattern::Bricks,
        Pattern::Gradient,
        Pattern::Noise,
    ];
    for (i, (at, half, yaw, shift, turn, group)) in boxes.into_iter().enumerate() {
        objects.push(standing(
            TOP_Y,
            [CENTRE[0] + at[0], CENTRE[1] + at[1]],
            half,
            yaw,
            (shift, turn),
            t(patterns[i], 0.1, mover_palette(i), 120 + i as u32),
            group,
        ));
    }
    let (camera_rotation, camera_translation) = orbit(&g, [CENTRE[0], TOP_Y, CENTRE[1]], 0.035);
    Built {
        objects: staged(&g, objects),
        camera_rotation,
        camera_translation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stage heights (y, metres) of the lowest point of `object` at both instants.
    fn lowest(object: &Object, g: &Isometry3<f64>) -> [f64; 2] {
        [0, 1].map(|time| {
            let points: Vec<Point3<f64>> = match &object.shape {
                Shape::Cuboid { half } => (0..8)
                    .map(|c| {
                        let s = |bit: usize| if c >> bit & 1 == 1 { 1.0 } else { -1.0 };
                        object.pose[time] * Point3::new(s(0) * half.x, s(1) * half.y, s(2) * half.z)
                    })
                    .collect(),
                Shape::Sheet(sheet) => sheet.vertices(time).to_vec(),
                Shape::Quad { .. } => unreachable!("no quad moves"),
            };
            let inverse = g.inverse();
            points
                .iter()
                .map(|p| (inverse * p).y)
                .fold(f64::NEG_INFINITY, f64::max)
        })
    }

    /// Every mover of the staged scenes stands on its support (floor, road, table top) in both
    /// frames: a mover in the air would have a scale that two views cannot observe.
    #[test]
    fn movers_stand_on_their_support_in_both_frames() {
        for (kind, pitch, support, movers) in [
            (SceneKind::Creature, CREATURE_PITCH, CREATURE_FLOOR, 5),
            (SceneKind::Road, ROAD_PITCH, ROAD_Y, 10),
            (SceneKind::Table, table_pitch(), TABLE_TOP, 1),
        ] {
            let g = stage(pitch);
            let built = build(kind);
            let moving: Vec<&Object> = built.objects.iter().filter(|o| o.group != 0).collect();
            assert_eq!(moving.len(), movers, "{kind:?}");
            // A body may have several parts (a car's body and cabin): its lowest point counts.
            let mut groups: Vec<u8> = moving.iter().map(|o| o.group).collect();
            groups.dedup();
            for group in groups {
                let low = moving
                    .iter()
                    .filter(|o| o.group == group)
                    .map(|o| lowest(o, &g))
                    .fold([f64::NEG_INFINITY; 2], |a, b| {
                        [a[0].max(b[0]), a[1].max(b[1])]
                    });
                for y in low {
                    assert!(
                        (y - support).abs() < 1e-9,
                        "{kind:?}: group {group} lowest at {y}, support at {support}"
                    );
                }
            }
        }
    }

    /// The creature bends but its feet stay put: the base ring is the same in both frames,
    /// and the rest of it moves.
    #[test]
    fn the_creature_bends_above_fixed_feet() {
        let built = build(SceneKind::Creature);
        let Some(Shape::Sheet(sheet)) = built
            .objects
            .iter()
            .map(|o| &o.shape)
            .find(|s| matches!(s, Shape::Sheet(_)))
        else {
            panic!("no creature");
        };
        let (before, after) = (sheet.vertices(0), sheet.vertices(1));
        let moved: Vec<f64> = before
            .iter()
            .zip(after)
            .map(|(a, b)| (a - b).norm())
            .collect();
        let cols = 48;
        assert!(moved[..cols].iter().all(|&d| d < 1e-12));
        let most = moved.iter().fold(0.0f64, |a, &d| a.max(d));
        // Measured: the head moves 0.10 m.
        assert!(most > 0.05 && most < 0.3, "head moves {most} m");
    }
}
