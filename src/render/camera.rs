//! The viewer's orbit camera: orbit, pan and zoom about a target point, the perspective
//! projection, and the home view that looks through camera 1 framed on the cloud.
//!
//! Conventions. World coordinates are camera 1's OpenCV frame (x right, y down, z forward), the
//! frame the point clouds come in; "up" on screen is world −y. Screen positions are in pixels of
//! the drawing buffer, u right and v down, pixel centres at integers (pixel (0, 0) covers
//! [−0.5, 0.5]²). Angles are radians. The projection follows wgpu: right-handed view space
//! (x right, y up, −z forward) and clip depth in [0, 1].
//!
//! With yaw = pitch = 0 the camera looks along +z; from the eye at the origin the projection is
//! the pinhole u = W/2 − 0.5 + f·x/z, v = H/2 − 0.5 + f·y/z with f = H / (2·tan(fov_y/2)), i.e.
//! camera 1 itself with a centred principal point.

use glam::camera::rh::{proj::directx::perspective, view::look_to_mat4};
use glam::{Mat4, Vec3, Vec4};

/// World "up" on screen: −y, because camera 1's y axis points down.
pub const WORLD_UP: Vec3 = Vec3::NEG_Y;

/// Largest |pitch|: just short of straight up or down, where the orbit would flip.
pub const MAX_PITCH: f32 = std::f32::consts::FRAC_PI_2 - 0.01;

/// Share of the half field of view that the home view fills with the cloud (the rest is margin).
pub const FRAMING_FILL: f32 = 0.95;

/// Points farther from the cloud's median than this many times the median distance are ignored
/// when framing the home view, so a few wild points do not push the camera far away.
pub const FRAMING_OUTLIER_FACTOR: f32 = 10.0;

/// Default vertical field of view: 50°, a typical phone camera held in landscape.
pub const DEFAULT_FOV_Y: f32 = 50.0 * std::f32::consts::PI / 180.0;

/// Size of the drawing buffer in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    pub width: f32,
    pub height: f32,
}

impl Viewport {
    /// Width over height (1 for an empty viewport).
    pub fn aspect(&self) -> f32 {
        if self.width > 0.0 && self.height > 0.0 {
            self.width / self.height
        } else {
            1.0
        }
    }
}

/// A sphere that contains the cloud (both frames), used for clip planes and zoom limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub centre: Vec3,
    pub radius: f32,
}

impl Bounds {
    /// The sphere around the axis-aligned bounding box of the finite `points`; a unit sphere at
    /// the origin when there are none. The radius is never zero (a single point gets a small
    /// sphere) so clip planes and zoom limits stay well defined.
    pub fn of_points<'a>(points: impl IntoIterator<Item = &'a [f32; 3]>) -> Bounds {
        Bounds::of_values(points.into_iter().copied())
    }

    /// [`Bounds::of_points`] of points given by value.
    pub fn of_values(points: impl IntoIterator<Item = [f32; 3]>) -> Bounds {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in points {
            let p = Vec3::from_array(p);
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if !lo.is_finite() {
            return Bounds {
                centre: Vec3::ZERO,
                radius: 1.0,
            };
        }
        let centre = (lo + hi) * 0.5;
        let floor = 1e-3 * (1.0 + centre.length());
        Bounds {
            centre,
            radius: ((hi - lo).length() * 0.5).max(floor),
        }
    }
}

/// An orbit camera: it looks at `target` from `distance` away, along the direction given by
/// `yaw` (about world up, positive turns the view to the right, +x) and `pitch` (positive looks
/// up, towards −y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub target: Vec3,
    pub distance: f32,
    pub yaw: f32,
    pub pitch: f32,
    /// Vertical field of view in radians.
    pub fov_y: f32,
}

impl Camera {
    /// Unit viewing direction in world coordinates.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, -sp, cy * cp)
    }

    /// Unit direction of screen right (+u) in world coordinates.
    pub fn right(&self) -> Vec3 {
        self.forward().cross(WORLD_UP).normalize()
    }

    /// Unit direction of screen up (−v) in world coordinates.
    pub fn up(&self) -> Vec3 {
        self.right().cross(self.forward())
    }

    /// Where the camera is, in world coordinates.
    pub fn eye(&self) -> Vec3 {
        self.target - self.forward() * self.distance
    }

    /// World → right-handed view space (x right, y up, −z forward).
    pub fn view_matrix(&self) -> Mat4 {
        look_to_mat4(self.eye(), self.forward(), WORLD_UP)
    }

    /// Near and far clip distances that keep all of `bounds` between them (with a little margin)
    /// and keep far/near ≤ 10⁴ for depth precision.
    pub fn clip_planes(&self, bounds: &Bounds) -> (f32, f32) {
        let depth_of_centre = (bounds.centre - self.eye()).dot(self.forward());
        let far = ((depth_of_centre + bounds.radius) * 1.01).max(1e-6);
        let near = ((depth_of_centre - bounds.radius) * 0.99).max(far * 1e-4);
        (near, far)
    }

    /// View space → clip space for `viewport`, with clip planes around `bounds`.
    pub fn projection_matrix(&self, viewport: Viewport, bounds: &Bounds) -> Mat4 {
        let (near, far) = self.clip_planes(bounds);
        perspective(self.fov_y, viewport.aspect(), near, far)
    }

    /// World → clip space: projection × view.
    pub fn view_projection(&self, viewport: Viewport, bounds: &Bounds) -> Mat4 {
        self.projection_matrix(viewport, bounds) * self.view_matrix()
    }

    /// Focal length in pixels of the projection: f = H / (2·tan(fov_y/2)).
    pub fn focal_px(&self, viewport: Viewport) -> f32 {
        viewport.height / (2.0 * (self.fov_y * 0.5).tan())
    }

    /// The pixel (u, v) where world point `p` lands and its clip depth in [0, 1]; `None` when
    /// the point is behind the eye or outside the near/far range.
    pub fn project(&self, p: Vec3, viewport: Viewport, bounds: &Bounds) -> Option<(f32, f32, f32)> {
        let clip = self.view_projection(viewport, bounds) * Vec4::from((p, 1.0));
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        if !(0.0..=1.0).contains(&ndc.z) {
            return None;
        }
        let u = (ndc.x + 1.0) * 0.5 * viewport.width - 0.5;
        let v = (1.0 - ndc.y) * 0.5 * viewport.height - 0.5;
        Some((u, v, ndc.z))
    }

    /// Turns the camera about its target by a drag of (`dx`, `dy`) pixels in a viewport `height`
    /// pixels tall: a drag over the full height turns by 180°. Dragging right moves the eye to
    /// the left (the scene follows the pointer); dragging down moves the eye up. The distance
    /// to the target is unchanged.
    pub fn orbit(&mut self, dx: f32, dy: f32, height: f32) {
        let per_px = std::f32::consts::PI / height.max(1.0);
        self.yaw = (self.yaw + dx * per_px).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch - dy * per_px).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Slides camera and target sideways so that the point under the pointer follows a drag of
    /// (`dx`, `dy`) pixels in a viewport `height` pixels tall (exact at the target's depth).
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let world_per_px = 2.0 * self.distance * (self.fov_y * 0.5).tan() / height.max(1.0);
        self.target += (self.up() * dy - self.right() * dx) * world_per_px;
    }

    /// Moves the eye towards the target (`factor` < 1) or away from it (`factor` > 1), keeping
    /// the distance within [radius/1000, radius·1000] of `bounds`.
    pub fn zoom(&mut self, factor: f32, bounds: &Bounds) {
        if factor.is_finite() && factor > 0.0 {
            self.distance =
                (self.distance * factor).clamp(bounds.radius * 1e-3, bounds.radius * 1e3);
        }
    }

    /// The home view: looking along +z (camera 1's optical axis) at the cloud's median depth,
    /// from camera 1's centre when the cloud fits in the field of view there, otherwise from as
    /// far behind it on the axis as needed to fit the whole cloud (points farther than
    /// [`FRAMING_OUTLIER_FACTOR`] × the median distance from the median are ignored).
    /// `fov_y` is in radians, `aspect` is width over height.
    pub fn home(points: &[[f32; 3]], fov_y: f32, aspect: f32) -> Camera {
        Camera::home_of(|| points.iter().copied(), fov_y, aspect)
    }

    /// [`Camera::home`] of the points that `points()` yields (called once per pass over them,
    /// the same points in the same order each time), so that a large cloud is framed without
    /// copying it: the only scratch is one `f32` per point.
    pub fn home_of<I: Iterator<Item = [f32; 3]>>(
        points: impl Fn() -> I,
        fov_y: f32,
        aspect: f32,
    ) -> Camera {
        let mut camera = Camera {
            target: Vec3::ZERO,
            distance: 1.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y,
        };
        // The finite points within FRAMING_OUTLIER_FACTOR × the median distance of the
        // per-axis median point.
        let finite = || points().map(Vec3::from_array).filter(|p| p.is_finite());
        let mut scratch: Vec<f32> = Vec::new();
        let mut median_of = |values: &mut dyn Iterator<Item = f32>| {
            scratch.clear();
            scratch.extend(values);
            (!scratch.is_empty()).then(|| median(&mut scratch))
        };
        let Some(x) = median_of(&mut finite().map(|p| p.x)) else {
            return camera;
        };
        let y = median_of(&mut finite().map(|p| p.y)).unwrap_or(0.0);
        let z = median_of(&mut finite().map(|p| p.z)).unwrap_or(0.0);
        let centre = Vec3::new(x, y, z);
        let limit = FRAMING_OUTLIER_FACTOR
            * median_of(&mut finite().map(|p| p.distance(centre))).unwrap_or(0.0);
        let inliers = || finite().filter(move |p| limit <= 0.0 || p.distance(centre) <= limit);
        let Some(z_centre) = median_of(&mut inliers().map(|p| p.z)) else {
            return camera;
        };
        let tan_v = (fov_y * 0.5).tan() * FRAMING_FILL;
        let tan_h = tan_v * aspect.max(1e-6);
        // The eye sits at (0, 0, z_centre − d); a point's view depth is then p.z − z_centre + d,
        // and it is in view when |x| ≤ tan_h · depth and |y| ≤ tan_v · depth.
        let bounds = Bounds::of_values(inliers().map(|p| p.to_array()));
        let min_depth = bounds.radius * 1e-3;
        let needed = inliers()
            .map(|p| {
                let lateral = (p.x.abs() / tan_h).max(p.y.abs() / tan_v).max(min_depth);
                lateral + z_centre - p.z
            })
            .fold(f32::NEG_INFINITY, f32::max);
        camera.target = Vec3::new(0.0, 0.0, z_centre);
        camera.distance = needed.max(z_centre).max(bounds.radius * 1e-3);
        camera
    }
}

/// The median of a non-empty slice of finite values (upper median for even lengths);
/// reorders the slice.
fn median(values: &mut [f32]) -> f32 {
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;

    const VIEWPORT: Viewport = Viewport {
        width: 640.0,
        height: 480.0,
    };

    fn camera_at_origin(fov_y: f32) -> Camera {
        Camera {
            target: Vec3::new(0.0, 0.0, 5.0),
            distance: 5.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y,
        }
    }

    fn unit_box_bounds() -> Bounds {
        Bounds {
            centre: Vec3::new(0.0, 0.0, 5.0),
            radius: 4.0,
        }
    }

    #[test]
    fn home_direction_is_camera_one() {
        let c = camera_at_origin(DEFAULT_FOV_Y);
        assert!(c.forward().abs_diff_eq(Vec3::Z, 1e-6));
        assert!(c.right().abs_diff_eq(Vec3::X, 1e-6));
        assert!(c.up().abs_diff_eq(Vec3::NEG_Y, 1e-6));
        assert!(c.eye().abs_diff_eq(Vec3::ZERO, 1e-6));
    }

    #[test]
    fn projection_through_camera_one_is_the_pinhole() {
        let c = camera_at_origin(0.9);
        let f = c.focal_px(VIEWPORT);
        let bounds = unit_box_bounds();
        for p in [
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(1.0, -0.5, 4.0),
            Vec3::new(-2.0, 1.5, 7.5),
            Vec3::new(0.3, 0.2, 2.0),
        ] {
            let (u, v, depth) = c.project(p, VIEWPORT, &bounds).unwrap();
            let expected_u = VIEWPORT.width / 2.0 - 0.5 + f * p.x / p.z;
            let expected_v = VIEWPORT.height / 2.0 - 0.5 + f * p.y / p.z;
            assert!((u - expected_u).abs() < 1e-3, "u {u} vs {expected_u}");
            assert!((v - expected_v).abs() < 1e-3, "v {v} vs {expected_v}");
            assert!((0.0..=1.0).contains(&depth));
        }
    }

    #[test]
    fn nearer_points_get_smaller_depth_and_points_behind_are_dropped() {
        let c = camera_at_origin(0.9);
        let bounds = unit_box_bounds();
        let near = c
            .project(Vec3::new(0.0, 0.0, 3.0), VIEWPORT, &bounds)
            .unwrap();
        let far = c
            .project(Vec3::new(0.0, 0.0, 8.0), VIEWPORT, &bounds)
            .unwrap();
        assert!(near.2 < far.2);
        assert!(
            c.project(Vec3::new(0.0, 0.0, -1.0), VIEWPORT, &bounds)
                .is_none()
        );
    }

    #[test]
    fn clip_planes_contain_the_bounds() {
        let mut c = camera_at_origin(0.9);
        let bounds = unit_box_bounds();
        for (yaw, pitch, distance) in [(0.0, 0.0, 5.0), (1.0, 0.4, 12.0), (3.0, -1.2, 0.5)] {
            c.yaw = yaw;
            c.pitch = pitch;
            c.distance = distance;
            let (near, far) = c.clip_planes(&bounds);
            let depth = (bounds.centre - c.eye()).dot(c.forward());
            assert!(near > 0.0 && near < far);
            assert!(far >= depth + bounds.radius);
            assert!(near <= (depth - bounds.radius).max(far));
            assert!(far / near <= 1.0001e4);
        }
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_target() {
        let mut c = camera_at_origin(0.9);
        let target = c.target;
        for (dx, dy) in [(40.0, 0.0), (0.0, 30.0), (-200.0, 90.0), (1000.0, -5000.0)] {
            c.orbit(dx, dy, VIEWPORT.height);
            assert!((c.eye().distance(target) - 5.0).abs() < 1e-4);
            assert_eq!(c.target, target);
            assert!(c.pitch.abs() <= MAX_PITCH);
        }
    }

    #[test]
    fn orbit_directions_follow_the_pointer() {
        let mut c = camera_at_origin(0.9);
        c.orbit(50.0, 0.0, VIEWPORT.height);
        assert!(c.eye().x < 0.0, "dragging right moves the eye left");
        let mut c = camera_at_origin(0.9);
        c.orbit(0.0, 50.0, VIEWPORT.height);
        assert!(c.eye().y < 0.0, "dragging down moves the eye up (−y)");
        // Half the viewport height turns by 90°.
        let mut c = camera_at_origin(0.9);
        c.orbit(VIEWPORT.height / 2.0, 0.0, VIEWPORT.height);
        assert!(c.forward().abs_diff_eq(Vec3::X, 1e-5));
    }

    #[test]
    fn pan_moves_the_target_point_with_the_pointer() {
        let bounds = unit_box_bounds();
        let mut c = camera_at_origin(0.9);
        let before = c.target;
        let (u0, v0, _) = c.project(before, VIEWPORT, &bounds).unwrap();
        c.pan(30.0, -20.0, VIEWPORT.height);
        assert_eq!(c.distance, 5.0);
        let (u1, v1, _) = c.project(before, VIEWPORT, &bounds).unwrap();
        assert!((u1 - u0 - 30.0).abs() < 1e-2, "u moved by {}", u1 - u0);
        assert!((v1 - v0 + 20.0).abs() < 1e-2, "v moved by {}", v1 - v0);
    }

    #[test]
    fn zoom_scales_the_distance_within_limits() {
        let bounds = unit_box_bounds();
        let mut c = camera_at_origin(0.9);
        c.zoom(0.5, &bounds);
        assert!((c.distance - 2.5).abs() < 1e-6);
        c.zoom(1e-9, &bounds);
        assert!((c.distance - bounds.radius * 1e-3).abs() < 1e-6);
        c.zoom(f32::NAN, &bounds);
        assert!((c.distance - bounds.radius * 1e-3).abs() < 1e-6);
        c.zoom(1e12, &bounds);
        assert!((c.distance - bounds.radius * 1e3).abs() < 1e-2);
    }

    /// A grid of points on two slanted planes in front of camera 1, within a 40° × 53° view.
    fn scene_points() -> Vec<[f32; 3]> {
        let mut points = Vec::new();
        for i in 0..20 {
            for j in 0..15 {
                let (s, t) = (i as f32 / 19.0 - 0.5, j as f32 / 14.0 - 0.5);
                let z = 4.0 + 2.0 * s;
                points.push([s * z * 0.6, t * z * 0.45, z]);
                points.push([s * 0.8, t * 0.6, 3.0 + t]);
            }
        }
        points
    }

    fn all_in_view(c: &Camera, points: &[[f32; 3]], viewport: Viewport) -> bool {
        let bounds = Bounds::of_points(points);
        points.iter().all(|p| {
            c.project(Vec3::from_array(*p), viewport, &bounds)
                .is_some_and(|(u, v, _)| {
                    (-0.5..viewport.width - 0.5).contains(&u)
                        && (-0.5..viewport.height - 0.5).contains(&v)
                })
        })
    }

    #[test]
    fn home_view_looks_through_camera_one_when_the_cloud_fits() {
        let points = scene_points();
        let c = Camera::home(&points, 60f32.to_radians(), VIEWPORT.aspect());
        assert!(c.eye().abs_diff_eq(Vec3::ZERO, 1e-4), "eye at {}", c.eye());
        assert!(c.forward().abs_diff_eq(Vec3::Z, 1e-6));
        assert!(all_in_view(&c, &points, VIEWPORT));
    }

    #[test]
    fn home_view_backs_off_to_fit_a_wide_cloud() {
        let points = scene_points();
        for (fov_deg, viewport) in [
            (20.0f32, VIEWPORT),
            (
                60.0,
                Viewport {
                    width: 100.0,
                    height: 400.0,
                },
            ),
        ] {
            let c = Camera::home(&points, fov_deg.to_radians(), viewport.aspect());
            assert!(c.eye().z < -0.1, "eye should move back, at {}", c.eye());
            assert!(c.eye().x.abs() < 1e-6 && c.eye().y.abs() < 1e-6);
            assert!(all_in_view(&c, &points, viewport));
        }
    }

    #[test]
    fn home_view_ignores_wild_outliers_and_non_finite_points() {
        let mut points = scene_points();
        let clean = Camera::home(&points, 60f32.to_radians(), VIEWPORT.aspect());
        points.push([1e6, -1e6, 5.0]);
        points.push([f32::NAN, 0.0, 1.0]);
        let with_outliers = Camera::home(&points, 60f32.to_radians(), VIEWPORT.aspect());
        assert!((clean.distance - with_outliers.distance).abs() < 1e-3);
        assert_eq!(clean.target, with_outliers.target);
    }

    #[test]
    fn home_view_of_nothing_is_finite() {
        let c = Camera::home(&[], DEFAULT_FOV_Y, 1.5);
        assert!(c.eye().is_finite());
        let one = Camera::home(&[[0.0, 0.0, 2.0]], DEFAULT_FOV_Y, 1.5);
        assert!(one.eye().abs_diff_eq(Vec3::ZERO, 1e-5));
    }

    #[test]
    fn bounds_contain_every_point() {
        let points = scene_points();
        let b = Bounds::of_points(&points);
        assert!(
            points
                .iter()
                .all(|p| Vec3::from_array(*p).distance(b.centre) <= b.radius + 1e-5)
        );
        let single = Bounds::of_points(&[[1.0, 2.0, 3.0]]);
        assert!(single.radius > 0.0);
        assert_eq!(Bounds::of_points(&[]).radius, 1.0);
    }
}
