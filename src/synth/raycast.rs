//! A small ray-caster over rigid quads and boxes and deforming triangle sheets, at two instants
//! (time 0 = frame 1, time 1 = frame 2). Every hit records where it lies on its surface (an
//! [`Anchor`]), so the same material point can be found at the other instant: that is what makes
//! the synthetic flow exact.
//!
//! World frame = camera 1's frame (x right, y down, z forward), units are metres.

use nalgebra::{Isometry3, Point3, Vector3};

use super::texture::Texture;

/// A ray `origin + λ·dir`; with `dir` of camera-frame z = 1, λ is the z-depth of the hit.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Point3<f64>,
    pub dir: Vector3<f64>,
}

/// Geometry of an object.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Rectangle `origin + s·u + t·v`, s, t ∈ [0, 1], in the object's frame; `u ⟂ v`.
    Quad {
        origin: Point3<f64>,
        u: Vector3<f64>,
        v: Vector3<f64>,
    },
    /// Axis-aligned box centred at the object's origin with these half extents.
    Cuboid { half: Vector3<f64> },
    /// A deforming triangle mesh, given in world coordinates at each instant.
    Sheet(Sheet),
}

/// A `cols × rows` grid of vertices triangulated into `2 (cols−1)(rows−1)` triangles, with vertex
/// positions at both instants and per-vertex material coordinates.
#[derive(Clone, Debug)]
pub struct Sheet {
    cols: usize,
    material: Vec<[f64; 2]>,
    positions: [Vec<Point3<f64>>; 2],
    tiles: [Vec<Tile>; 2],
}

/// A block of mesh cells with its bounding box, to skip most triangles quickly.
#[derive(Clone, Debug)]
struct Tile {
    min: Point3<f64>,
    max: Point3<f64>,
    cells: (std::ops::Range<usize>, std::ops::Range<usize>),
}

/// Mesh cells per tile side.
const TILE: usize = 6;

impl Sheet {
    /// A sheet whose vertex (i, j) (i < cols along the first material axis) is at
    /// `position(i, j, time)` with material coordinates `material(i, j)`.
    pub fn new(
        cols: usize,
        rows: usize,
        material: impl Fn(usize, usize) -> [f64; 2],
        position: impl Fn(usize, usize, usize) -> Point3<f64>,
    ) -> Self {
        let grid = |f: &dyn Fn(usize, usize) -> Point3<f64>| -> Vec<Point3<f64>> {
            (0..rows)
                .flat_map(|j| (0..cols).map(move |i| (i, j)))
                .map(|(i, j)| f(i, j))
                .collect()
        };
        let positions = [
            grid(&|i, j| position(i, j, 0)),
            grid(&|i, j| position(i, j, 1)),
        ];
        let material = (0..rows)
            .flat_map(|j| (0..cols).map(move |i| (i, j)))
            .map(|(i, j)| material(i, j))
            .collect();
        let tiles = [
            Self::tiles(cols, rows, &positions[0]),
            Self::tiles(cols, rows, &positions[1]),
        ];
        Sheet {
            cols,
            material,
            positions,
            tiles,
        }
    }

    /// Vertex positions at `time`, row by row.
    #[cfg(test)]
    pub fn vertices(&self, time: usize) -> &[Point3<f64>] {
        &self.positions[time]
    }

    /// The same sheet with every vertex moved by `g` at both instants (a sheet ignores its
    /// object's pose, so this is how a sheet built in another frame is placed in the world).
    pub fn moved(&self, g: &Isometry3<f64>) -> Self {
        let rows = self.material.len() / self.cols;
        let positions = self
            .positions
            .clone()
            .map(|p| p.iter().map(|x| g * x).collect::<Vec<_>>());
        let tiles = [
            Self::tiles(self.cols, rows, &positions[0]),
            Self::tiles(self.cols, rows, &positions[1]),
        ];
        Sheet {
            cols: self.cols,
            material: self.material.clone(),
            positions,
            tiles,
        }
    }

    fn tiles(cols: usize, rows: usize, pos: &[Point3<f64>]) -> Vec<Tile> {
        let mut tiles = Vec::new();
        for j0 in (0..rows - 1).step_by(TILE) {
            for i0 in (0..cols - 1).step_by(TILE) {
                let (i1, j1) = ((i0 + TILE).min(cols - 1), (j0 + TILE).min(rows - 1));
                let mut min = Point3::from([f64::INFINITY; 3]);
                let mut max = Point3::from([f64::NEG_INFINITY; 3]);
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let p = pos[j * cols + i];
                        min = min.inf(&p);
                        max = max.sup(&p);
                    }
                }
                tiles.push(Tile {
                    min,
                    max,
                    cells: (i0..i1, j0..j1),
                });
            }
        }
        tiles
    }

    /// The three vertex indices of triangle `tri` (two per cell).
    fn triangle(&self, tri: usize) -> [usize; 3] {
        let (cell, upper) = (tri / 2, tri % 2 == 1);
        let (i, j) = (cell % (self.cols - 1), cell / (self.cols - 1));
        let a = j * self.cols + i;
        if upper {
            [a + 1, a + self.cols + 1, a + self.cols]
        } else {
            [a, a + 1, a + self.cols]
        }
    }

    fn intersect(&self, ray: &Ray, time: usize, best: f64) -> Option<(f64, Anchor)> {
        let mut found: Option<(f64, Anchor)> = None;
        let mut limit = best;
        for tile in &self.tiles[time] {
            if !ray_hits_box(ray, &tile.min, &tile.max, limit) {
                continue;
            }
            for j in tile.cells.1.clone() {
                for i in tile.cells.0.clone() {
                    for upper in 0..2 {
                        let tri = 2 * (j * (self.cols - 1) + i) + upper;
                        let [a, b, c] = self.triangle(tri).map(|v| self.positions[time][v]);
                        if let Some((lambda, w1, w2)) = ray_triangle(ray, &a, &b, &c)
                            && lambda < limit
                        {
                            limit = lambda;
                            found = Some((
                                lambda,
                                Anchor::Mesh {
                                    tri,
                                    bary: [1.0 - w1 - w2, w1, w2],
                                },
                            ));
                        }
                    }
                }
            }
        }
        found
    }

    fn point(&self, tri: usize, bary: [f64; 3], time: usize) -> Point3<f64> {
        let v = self.triangle(tri);
        let p = &self.positions[time];
        Point3::from(p[v[0]].coords * bary[0] + p[v[1]].coords * bary[1] + p[v[2]].coords * bary[2])
    }

    fn material(&self, tri: usize, bary: [f64; 3]) -> [f64; 2] {
        let v = self.triangle(tri);
        let m = |k: usize| {
            self.material[v[0]][k] * bary[0]
                + self.material[v[1]][k] * bary[1]
                + self.material[v[2]][k] * bary[2]
        };
        [m(0), m(1)]
    }
}

/// Where on its object a hit lies, independent of time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Anchor {
    /// A point in a rigid object's own frame.
    Local(Point3<f64>),
    /// A point on a sheet: triangle index and barycentric weights.
    Mesh { tri: usize, bary: [f64; 3] },
}

/// An object of the scene: geometry, its pose at both instants (ignored for sheets),
/// texture, and motion group (0 = static world).
#[derive(Clone, Debug)]
pub struct Object {
    pub shape: Shape,
    pub pose: [Isometry3<f64>; 2],
    /// `pose[t].inverse()`, cached: rays are moved into the object's frame.
    inverse: [Isometry3<f64>; 2],
    pub texture: Texture,
    pub group: u8,
}

/// The nearest surface along a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter λ of the hit (the z-depth when the ray's camera-frame z is 1).
    pub lambda: f64,
    pub object: usize,
    pub anchor: Anchor,
}

/// Per-face brightness of boxes, so adjacent faces differ.
const FACE_TINT: [f64; 6] = [0.92, 0.8, 1.0, 0.7, 0.86, 0.76];

impl Object {
    /// A static or moving rigid object.
    pub fn rigid(
        shape: Shape,
        pose0: Isometry3<f64>,
        pose1: Isometry3<f64>,
        texture: Texture,
        group: u8,
    ) -> Self {
        Object {
            shape,
            pose: [pose0, pose1],
            inverse: [pose0.inverse(), pose1.inverse()],
            texture,
            group,
        }
    }

    fn intersect(&self, ray: &Ray, time: usize, best: f64) -> Option<(f64, Anchor)> {
        if let Shape::Sheet(sheet) = &self.shape {
            return sheet.intersect(ray, time, best);
        }
        let inv = &self.inverse[time];
        let local = Ray {
            origin: inv * ray.origin,
            dir: inv * ray.dir,
        };
        let lambda = match &self.shape {
            Shape::Quad { origin, u, v } => ray_quad(&local, origin, u, v)?,
            Shape::Cuboid { half } => ray_cuboid(&local, half)?,
            Shape::Sheet(_) => return None,
        };
        (lambda < best).then(|| (lambda, Anchor::Local(local.origin + local.dir * lambda)))
    }

    /// World position of an anchor at `time`.
    pub fn world_point(&self, anchor: &Anchor, time: usize) -> Point3<f64> {
        match (anchor, &self.shape) {
            (Anchor::Mesh { tri, bary }, Shape::Sheet(sheet)) => sheet.point(*tri, *bary, time),
            (Anchor::Local(p), _) => self.pose[time] * p,
            (Anchor::Mesh { .. }, _) => Point3::origin(),
        }
    }

    /// Surface colour in [0, 1] at an anchor.
    pub fn colour(&self, anchor: &Anchor) -> [f64; 3] {
        match (anchor, &self.shape) {
            (Anchor::Mesh { tri, bary }, Shape::Sheet(sheet)) => {
                let [a, b] = sheet.material(*tri, *bary);
                self.texture.colour(a, b, 1.0)
            }
            (Anchor::Local(p), Shape::Quad { origin, u, v }) => {
                let d = p - origin;
                self.texture
                    .colour(d.dot(u) / u.norm(), d.dot(v) / v.norm(), 1.0)
            }
            (Anchor::Local(p), Shape::Cuboid { half }) => {
                let face = cuboid_face(p, half);
                let (a, b) = match face / 2 {
                    0 => (p.z + half.z, p.y + half.y),
                    1 => (p.x + half.x, p.z + half.z),
                    _ => (p.x + half.x, p.y + half.y),
                };
                self.texture
                    .colour(a + face as f64 * 3.1, b, FACE_TINT[face])
            }
            _ => [0.0; 3],
        }
    }
}

/// The nearest hit among `objects` at `time`.
pub fn cast(objects: &[Object], ray: &Ray, time: usize) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (index, object) in objects.iter().enumerate() {
        let limit = best.map_or(f64::INFINITY, |h| h.lambda);
        if let Some((lambda, anchor)) = object.intersect(ray, time, limit) {
            best = Some(Hit {
                lambda,
                object: index,
                anchor,
            });
        }
    }
    best
}

const EPS: f64 = 1e-9;

fn ray_quad(ray: &Ray, origin: &Point3<f64>, u: &Vector3<f64>, v: &Vector3<f64>) -> Option<f64> {
    let n = u.cross(v);
    let denom = ray.dir.dot(&n);
    if denom.abs() < EPS {
        return None;
    }
    let lambda = (origin - ray.origin).dot(&n) / denom;
    if lambda <= EPS {
        return None;
    }
    let d = ray.origin + ray.dir * lambda - origin;
    let (s, t) = (d.dot(u) / u.norm_squared(), d.dot(v) / v.norm_squared());
    ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)).then_some(lambda)
}

/// Entry distance into an axis-aligned box centred at the origin (seen from outside).
fn ray_cuboid(ray: &Ray, half: &Vector3<f64>) -> Option<f64> {
    let (near, far) = slab(ray, &Point3::from(-half), &Point3::from(*half))?;
    (near > EPS && near <= far).then_some(near)
}

fn slab(ray: &Ray, min: &Point3<f64>, max: &Point3<f64>) -> Option<(f64, f64)> {
    let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let inv = 1.0 / ray.dir[k];
        let (a, b) = (
            (min[k] - ray.origin[k]) * inv,
            (max[k] - ray.origin[k]) * inv,
        );
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        near = near.max(a);
        far = far.min(b);
        if near > far || far.is_nan() {
            return None;
        }
    }
    Some((near, far))
}

fn ray_hits_box(ray: &Ray, min: &Point3<f64>, max: &Point3<f64>, limit: f64) -> bool {
    let pad = Vector3::repeat(1e-6);
    slab(ray, &(min - pad), &(max + pad)).is_some_and(|(near, far)| far > EPS && near < limit)
}

/// Which face of the box a surface point lies on: 2·axis + (1 if on the positive side).
fn cuboid_face(p: &Point3<f64>, half: &Vector3<f64>) -> usize {
    let mut best = (f64::INFINITY, 0);
    for k in 0..3 {
        for (side, target) in [(0, -half[k]), (1, half[k])] {
            let d = (p[k] - target).abs();
            if d < best.0 {
                best = (d, 2 * k + side);
            }
        }
    }
    best.1
}

/// Möller–Trumbore: (λ, w1, w2) of the hit, two-sided.
fn ray_triangle(
    ray: &Ray,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = ray.dir.cross(&e2);
    let det = e1.dot(&p);
    if det.abs() < 1e-14 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - a;
    let w1 = s.dot(&p) * inv;
    if !(0.0..=1.0).contains(&w1) {
        return None;
    }
    let q = s.cross(&e1);
    let w2 = ray.dir.dot(&q) * inv;
    if w2 < 0.0 || w1 + w2 > 1.0 {
        return None;
    }
    let lambda = e2.dot(&q) * inv;
    (lambda > EPS).then_some((lambda, w1, w2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::texture::Pattern;

    fn texture() -> Texture {
        Texture::new(Pattern::Noise, 1.0, [[0.5; 3]; 3], 1)
    }

    fn ray_to(p: Point3<f64>) -> Ray {
        Ray {
            origin: Point3::origin(),
            dir: p.coords / p.z,
        }
    }

    #[test]
    fn quad_box_and_sheet_hits_land_on_the_surface() {
        let id = Isometry3::identity();
        let quad = Object::rigid(
            Shape::Quad {
                origin: Point3::new(-5.0, -5.0, 10.0),
                u: Vector3::new(10.0, 0.0, 0.0),
                v: Vector3::new(0.0, 10.0, 0.0),
            },
            id,
            id,
            texture(),
            0,
        );
        let cube = Object::rigid(
            Shape::Cuboid {
                half: Vector3::new(1.0, 1.0, 1.0),
            },
            Isometry3::translation(0.0, 0.0, 5.0),
            id,
            texture(),
            1,
        );
        let sheet = Object::rigid(
            Shape::Sheet(Sheet::new(
                13,
                13,
                |i, j| [i as f64, j as f64],
                |i, j, _| Point3::new(i as f64 * 0.1 + 1.5, j as f64 * 0.1 - 0.6, 3.0),
            )),
            id,
            id,
            texture(),
            2,
        );
        let objects = [quad, cube, sheet];
        let h = cast(&objects, &ray_to(Point3::new(0.2, 0.1, 1.0)), 0).unwrap();
        assert_eq!(h.object, 1);
        assert!((h.lambda - 4.0).abs() < 1e-12);
        let h = cast(&objects, &ray_to(Point3::new(2.0, 0.0, 3.0)), 0).unwrap();
        assert_eq!(h.object, 2);
        assert!((objects[2].world_point(&h.anchor, 0) - Point3::new(2.0, 0.0, 3.0)).norm() < 1e-12);
        let h = cast(&objects, &ray_to(Point3::new(-4.0, 3.0, 10.0)), 0).unwrap();
        assert_eq!(h.object, 0);
        assert!((h.lambda - 10.0).abs() < 1e-12);
        assert!(cast(&objects, &ray_to(Point3::new(-6.0, 0.0, 10.0)), 0).is_none());
    }

    #[test]
    fn rigid_anchor_follows_the_motion() {
        let pose1 = Isometry3::new(Vector3::new(0.5, 0.0, 1.0), Vector3::new(0.0, 0.3, 0.0));
        let cube = Object::rigid(
            Shape::Cuboid {
                half: Vector3::new(1.0, 1.0, 1.0),
            },
            Isometry3::translation(0.0, 0.0, 5.0),
            pose1,
            texture(),
            1,
        );
        let h = cast(
            std::slice::from_ref(&cube),
            &ray_to(Point3::new(0.1, 0.05, 1.0)),
            0,
        )
        .unwrap();
        let p0 = cube.world_point(&h.anchor, 0);
        let p1 = cube.world_point(&h.anchor, 1);
        let expected = pose1 * (Isometry3::translation(0.0, 0.0, 5.0).inverse() * p0);
        assert!((p1 - expected).norm() < 1e-12);
    }
}
