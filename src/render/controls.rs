//! Pointer gestures → camera moves: one pointer orbits (or pans with the secondary/middle
//! button or a modifier key), two pointers (touch) pinch to zoom and move together to pan, the
//! wheel zooms.
//!
//! Positions are in CSS pixels relative to the canvas (u right, v down); `height` is the canvas
//! height in the same unit. The browser side only forwards pointer and wheel events.

use super::camera::{Bounds, Camera};

/// Zoom factor per wheel pixel: exp(0.002 · Δ), so a 100-pixel wheel notch zooms by about 22 %.
pub const WHEEL_ZOOM_PER_PX: f32 = 0.002;

/// What a single-pointer drag does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    Orbit,
    Pan,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Pointer {
    id: i32,
    x: f32,
    y: f32,
    drag: Drag,
}

/// The pointers currently pressed on the canvas (at most two are tracked; more are ignored).
#[derive(Clone, Debug, Default)]
pub struct Controls {
    pointers: Vec<Pointer>,
}

impl Controls {
    /// A pointer `id` went down at (`x`, `y`); `drag` is what moving it alone will do.
    pub fn pointer_down(&mut self, id: i32, x: f32, y: f32, drag: Drag) {
        self.pointers.retain(|p| p.id != id);
        if self.pointers.len() < 2 {
            self.pointers.push(Pointer { id, x, y, drag });
        }
    }

    /// A pointer went up or was cancelled.
    pub fn pointer_up(&mut self, id: i32) {
        self.pointers.retain(|p| p.id != id);
    }

    /// Whether any pointer is pressed (a drag or pinch is under way).
    pub fn is_active(&self) -> bool {
        !self.pointers.is_empty()
    }

    /// Pointer `id` moved to (`x`, `y`): orbits, pans or pinches `camera`. Returns whether the
    /// camera changed (false for pointers that are not pressed).
    pub fn pointer_move(
        &mut self,
        id: i32,
        x: f32,
        y: f32,
        camera: &mut Camera,
        height: f32,
        bounds: &Bounds,
    ) -> bool {
        let Some(index) = self.pointers.iter().position(|p| p.id == id) else {
            return false;
        };
        let before = self.pointers.clone();
        self.pointers[index].x = x;
        self.pointers[index].y = y;
        let after = &self.pointers;
        match (before.as_slice(), after.as_slice()) {
            ([old], [new]) => {
                let (dx, dy) = (new.x - old.x, new.y - old.y);
                match new.drag {
                    Drag::Orbit => camera.orbit(dx, dy, height),
                    Drag::Pan => camera.pan(dx, dy, height),
                }
            }
            ([a0, b0], [a1, b1]) => {
                let spread0 = (a0.x - b0.x).hypot(a0.y - b0.y);
                let spread1 = (a1.x - b1.x).hypot(a1.y - b1.y);
                if spread0 > 1.0 && spread1 > 1.0 {
                    camera.zoom(spread0 / spread1, bounds);
                }
                let mid = |a: &Pointer, b: &Pointer| ((a.x + b.x) * 0.5, (a.y + b.y) * 0.5);
                let ((mx0, my0), (mx1, my1)) = (mid(a0, b0), mid(a1, b1));
                camera.pan(mx1 - mx0, my1 - my0, height);
            }
            _ => return false,
        }
        true
    }

    /// A wheel turn of `delta_y` pixels (positive: towards the user, zooms out).
    pub fn wheel(&self, delta_y: f32, camera: &mut Camera, bounds: &Bounds) {
        camera.zoom((delta_y * WHEEL_ZOOM_PER_PX).exp(), bounds);
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    const HEIGHT: f32 = 400.0;

    fn setup() -> (Camera, Bounds) {
        let camera = Camera {
            target: Vec3::new(0.0, 0.0, 5.0),
            distance: 5.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 0.8,
        };
        let bounds = Bounds {
            centre: camera.target,
            radius: 2.0,
        };
        (camera, bounds)
    }

    #[test]
    fn one_pointer_orbits_like_the_camera_orbit() {
        let (mut camera, bounds) = setup();
        let mut expected = camera;
        expected.orbit(25.0, -10.0, HEIGHT);
        let mut controls = Controls::default();
        controls.pointer_down(1, 100.0, 100.0, Drag::Orbit);
        assert!(controls.pointer_move(1, 125.0, 90.0, &mut camera, HEIGHT, &bounds));
        assert_eq!(camera, expected);
        controls.pointer_up(1);
        assert!(!controls.is_active());
        assert!(!controls.pointer_move(1, 300.0, 90.0, &mut camera, HEIGHT, &bounds));
        assert_eq!(camera, expected);
    }

    #[test]
    fn pan_drag_moves_the_target_and_keeps_the_direction() {
        let (mut camera, bounds) = setup();
        let mut controls = Controls::default();
        controls.pointer_down(4, 10.0, 10.0, Drag::Pan);
        controls.pointer_move(4, 40.0, 10.0, &mut camera, HEIGHT, &bounds);
        assert!(camera.target.x < 0.0, "dragging right moves the view left");
        assert_eq!((camera.yaw, camera.pitch, camera.distance), (0.0, 0.0, 5.0));
    }

    #[test]
    fn spreading_two_fingers_zooms_in_and_moving_them_together_pans() {
        let (mut camera, bounds) = setup();
        let mut controls = Controls::default();
        controls.pointer_down(1, 100.0, 200.0, Drag::Orbit);
        controls.pointer_down(2, 200.0, 200.0, Drag::Orbit);
        // Spread from 100 to 200 pixels apart about the same midpoint: twice as close.
        controls.pointer_move(1, 50.0, 200.0, &mut camera, HEIGHT, &bounds);
        controls.pointer_move(2, 250.0, 200.0, &mut camera, HEIGHT, &bounds);
        assert!(
            (camera.distance - 2.5).abs() < 1e-4,
            "distance {}",
            camera.distance
        );
        assert_eq!((camera.yaw, camera.pitch), (0.0, 0.0));
        // Both fingers move down by 20 pixels: a pan, no zoom, no orbit.
        let distance = camera.distance;
        controls.pointer_move(1, 50.0, 220.0, &mut camera, HEIGHT, &bounds);
        controls.pointer_move(2, 250.0, 220.0, &mut camera, HEIGHT, &bounds);
        assert!((camera.distance - distance).abs() < 1e-3);
        assert!(
            camera.target.y < 0.0,
            "dragging down moves the view up (−y)"
        );
        assert_eq!((camera.yaw, camera.pitch), (0.0, 0.0));
    }

    #[test]
    fn a_third_finger_is_ignored_and_lifting_one_returns_to_orbit() {
        let (mut camera, bounds) = setup();
        let mut controls = Controls::default();
        controls.pointer_down(1, 0.0, 0.0, Drag::Orbit);
        controls.pointer_down(2, 100.0, 0.0, Drag::Orbit);
        controls.pointer_down(3, 50.0, 50.0, Drag::Orbit);
        assert!(!controls.pointer_move(3, 80.0, 80.0, &mut camera, HEIGHT, &bounds));
        controls.pointer_up(2);
        assert!(controls.pointer_move(1, 10.0, 0.0, &mut camera, HEIGHT, &bounds));
        assert!(camera.yaw > 0.0);
    }

    #[test]
    fn wheel_down_zooms_out_and_up_zooms_in() {
        let (mut camera, bounds) = setup();
        let controls = Controls::default();
        controls.wheel(100.0, &mut camera, &bounds);
        assert!(camera.distance > 5.0);
        controls.wheel(-200.0, &mut camera, &bounds);
        assert!(camera.distance < 5.0);
    }
}
