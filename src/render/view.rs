//! Everything the viewer shows and how, independent of the GPU: the cloud and the subset of it
//! that is drawn, the point colours, the camera and its gestures, and the display settings.
//! The GPU part (`gpu`, wasm only) uploads what this produces: the packed points, a slice at a
//! time ([`View::pack_positions`], [`View::pack_colours`]) when their version changes, and the
//! [`Uniforms`] every frame. The view keeps no packed copy of the cloud: a 1024 × 768
//! reconstruction is 786 432 points, 24 MB as a [`PointCloud`], and its packed form would be
//! another 31 MB.

use super::{RenderError, Result};

use super::camera::{Bounds, Camera, DEFAULT_FOV_Y, Viewport};
use super::cloud::PointCloud;
use super::colour::{ColourMode, Colouring};
use super::controls::{Controls, Drag};
use super::decimate::{DESKTOP_POINT_BUDGET, decimate};

/// Default point size in CSS pixels.
pub const DEFAULT_POINT_SIZE: f32 = 2.0;

/// Largest point size in CSS pixels.
pub const MAX_POINT_SIZE: f32 = 64.0;

/// Default background: the page's dark header colour.
pub const DEFAULT_BACKGROUND: [u8; 3] = [0x1d, 0x23, 0x30];

/// How the points of flagged superpixels (e.g. those whose scale is unknown) are shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FlagStyle {
    /// Like every other point.
    #[default]
    Show,
    /// In [`FLAG_COLOUR`], whatever the colour mode.
    Mark,
    /// Not drawn.
    Hide,
}

impl std::str::FromStr for FlagStyle {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "show" => Ok(FlagStyle::Show),
            "mark" => Ok(FlagStyle::Mark),
            "hide" => Ok(FlagStyle::Hide),
            other => Err(RenderError::InvalidParameter(format!(
                "flagged points are \"show\", \"mark\" or \"hide\", not {other:?}"
            ))),
        }
    }
}

/// Flagged superpixel labels must be below this (a reconstruction has thousands).
pub const MAX_FLAGGED_LABEL: u32 = 1 << 24;

/// The colour of marked points: magenta, the tint of the page's confidence picture
/// (`output::confidence_picture`).
pub const FLAG_COLOUR: [u8; 4] = [255, 0, 200, 255];

/// The per-frame shader parameters, laid out as the WGSL `Uniforms` struct of `points.wgsl`
/// (80 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uniforms {
    /// World → clip space, column-major.
    pub view_projection: [f32; 16],
    /// Drawing-buffer size in pixels.
    pub viewport_px: [f32; 2],
    /// Point side length in drawing-buffer pixels.
    pub point_size_px: f32,
    /// Morph parameter t: points are drawn at X + t·(X' − X).
    pub morph: f32,
}

impl Uniforms {
    /// Size of the uniform block in bytes.
    pub const SIZE: usize = 80;

    /// The little-endian bytes of the uniform block, as the shader reads them.
    pub fn to_bytes(&self) -> [u8; Self::SIZE] {
        let mut out = [0u8; Self::SIZE];
        let values = self
            .view_projection
            .iter()
            .chain(&self.viewport_px)
            .chain([&self.point_size_px, &self.morph]);
        for (chunk, v) in out.chunks_exact_mut(4).zip(values) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        out
    }
}

/// The viewer's state. All lengths on screen are in CSS pixels except where a name says `_px`
/// (drawing-buffer pixels = CSS pixels × device pixel ratio).
#[derive(Clone, Debug)]
pub struct View {
    cloud: PointCloud,
    /// Indices of the drawn points (ascending), or `None` when every point is drawn.
    shown: Option<Vec<u32>>,
    budget: usize,
    colour_mode: ColourMode,
    /// The colour map's inverse-depth range (of the whole cloud's frame-1 depths).
    depth_range: (f32, f32),
    /// Per superpixel label: whether its points are flagged (labels past the end are not).
    flagged: Vec<bool>,
    flag_style: FlagStyle,
    positions_version: u64,
    colours_version: u64,
    bounds: Bounds,
    camera: Camera,
    /// The last home view; while the camera is still there, a new aspect ratio re-frames it.
    home: Camera,
    controls: Controls,
    fov_y: f32,
    viewport: Viewport,
    pixel_ratio: f32,
    point_size: f32,
    morph: f32,
    background: [u8; 3],
}

impl Default for View {
    fn default() -> Self {
        View::new(DESKTOP_POINT_BUDGET)
    }
}

impl View {
    /// An empty view that draws at most `budget` points.
    pub fn new(budget: usize) -> View {
        let viewport = Viewport {
            width: 1.0,
            height: 1.0,
        };
        let mut view = View {
            cloud: PointCloud::default(),
            shown: None,
            budget: budget.max(1),
            colour_mode: ColourMode::Rgb,
            depth_range: (0.0, 1.0),
            flagged: Vec::new(),
            flag_style: FlagStyle::Show,
            positions_version: 0,
            colours_version: 0,
            bounds: Bounds::of_points(&[]),
            camera: Camera::home(&[], DEFAULT_FOV_Y, 1.0),
            home: Camera::home(&[], DEFAULT_FOV_Y, 1.0),
            controls: Controls::default(),
            fov_y: DEFAULT_FOV_Y,
            viewport,
            pixel_ratio: 1.0,
            point_size: DEFAULT_POINT_SIZE,
            morph: 0.0,
            background: DEFAULT_BACKGROUND,
        };
        view.reset_view();
        view
    }

    /// Shows `cloud` from the home view. A superpixel colour mode falls back to RGB when the new
    /// cloud has no labels.
    pub fn set_cloud(&mut self, cloud: PointCloud) {
        self.cloud = cloud;
        if self.colour_mode == ColourMode::Superpixel && self.cloud.labels().is_none() {
            self.colour_mode = ColourMode::Rgb;
        }
        self.depth_range = Colouring::depth_range(&self.cloud);
        self.select_points();
        self.bounds = Bounds::of_points(self.cloud.pos1().iter().chain(self.cloud.pos2()));
        self.reset_view();
    }

    /// Flags the points of the superpixels `labels` (replacing earlier flags; they stay for
    /// later clouds) and shows flagged points in `style`. Points of a cloud without labels are
    /// never flagged. Hiding keeps the camera where it is. Fails, changing nothing, for a label
    /// of [`MAX_FLAGGED_LABEL`] or more.
    pub fn set_flagged(&mut self, labels: &[u32], style: FlagStyle) -> Result<()> {
        if let Some(&label) = labels.iter().find(|&&l| l >= MAX_FLAGGED_LABEL) {
            return Err(RenderError::InvalidParameter(format!(
                "superpixel label {label} is too large to flag (at most {})",
                MAX_FLAGGED_LABEL - 1
            )));
        }
        let len = labels.iter().max().map_or(0, |&l| l as usize + 1);
        self.flagged = vec![false; len];
        for &label in labels {
            self.flagged[label as usize] = true;
        }
        self.flag_style = style;
        self.select_points();
        Ok(())
    }

    /// Whether point `i` of the cloud is flagged.
    fn is_flagged(&self, i: usize) -> bool {
        self.cloud
            .labels()
            .and_then(|labels| self.flagged.get(labels[i] as usize))
            .copied()
            .unwrap_or(false)
    }

    /// Takes the cloud out (the view is left empty), e.g. to free its memory before a new one
    /// is built. The colour mode stays for that next cloud (the empty one in between has no
    /// labels, which would otherwise end a superpixel colouring).
    pub fn take_cloud(&mut self) -> PointCloud {
        let mode = self.colour_mode;
        let cloud = std::mem::take(&mut self.cloud);
        self.set_cloud(PointCloud::default());
        self.colour_mode = mode;
        cloud
    }

    /// Puts the camera where `camera` says (e.g. the camera of an earlier viewer of the same
    /// cloud); the field of view stays this view's.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = Camera {
            fov_y: self.fov_y,
            ..camera
        };
    }

    /// Draws at most `budget` points (at least 1); larger clouds are decimated
    /// ([`decimate`]).
    pub fn set_point_budget(&mut self, budget: usize) {
        let budget = budget.max(1);
        if budget != self.budget {
            self.budget = budget;
            self.select_points();
        }
    }

    /// Recolours the points. Fails, leaving the mode unchanged, for superpixel colours on a
    /// cloud without labels.
    pub fn set_colour_mode(&mut self, mode: ColourMode) -> Result<()> {
        Colouring::new(&self.cloud, mode, self.depth_range)?;
        self.colour_mode = mode;
        self.colours_version += 1;
        Ok(())
    }

    /// Morph parameter t in [0, 1]: 0 shows frame 1, 1 shows frame 2, in between the points
    /// move along straight lines X + t·(X' − X).
    pub fn set_morph(&mut self, t: f32) -> Result<()> {
        if !(0.0..=1.0).contains(&t) {
            return Err(RenderError::InvalidParameter(format!(
                "morph must be between 0 (frame 1) and 1 (frame 2), not {t}"
            )));
        }
        self.morph = t;
        Ok(())
    }

    /// Shows frame 1 or frame 2 (morph 0 or 1).
    pub fn set_frame(&mut self, frame: u32) -> Result<()> {
        match frame {
            1 => self.set_morph(0.0),
            2 => self.set_morph(1.0),
            other => Err(RenderError::InvalidParameter(format!(
                "frame must be 1 or 2, not {other}"
            ))),
        }
    }

    /// Point side length in CSS pixels, clamped to [1, [`MAX_POINT_SIZE`]].
    pub fn set_point_size(&mut self, size: f32) -> Result<()> {
        if !size.is_finite() || size <= 0.0 {
            return Err(RenderError::InvalidParameter(format!(
                "point size must be a positive number of pixels, not {size}"
            )));
        }
        self.point_size = size.clamp(1.0, MAX_POINT_SIZE);
        Ok(())
    }

    /// Vertical field of view in degrees (in (0, 180)), e.g. 2·atan(H / (2·fy)) for a photo of
    /// height H pixels taken with focal length fy pixels, so that the home view matches camera 1.
    /// Takes effect at the next [`View::reset_view`].
    pub fn set_field_of_view(&mut self, degrees: f32) -> Result<()> {
        if !(degrees > 0.0 && degrees < 180.0) {
            return Err(RenderError::InvalidParameter(format!(
                "field of view must be between 0 and 180 degrees, not {degrees}"
            )));
        }
        self.fov_y = degrees.to_radians();
        Ok(())
    }

    /// Background colour (sRGB bytes).
    pub fn set_background(&mut self, rgb: [u8; 3]) {
        self.background = rgb;
    }

    /// The drawing buffer is `width_px` × `height_px` pixels with `pixel_ratio` pixels per CSS
    /// pixel. While the user has not moved the camera from the home view, a new aspect ratio
    /// re-frames the home view.
    pub fn set_viewport(&mut self, width_px: u32, height_px: u32, pixel_ratio: f32) {
        let viewport = Viewport {
            width: width_px.max(1) as f32,
            height: height_px.max(1) as f32,
        };
        let aspect_changed = viewport.aspect() != self.viewport.aspect();
        self.viewport = viewport;
        if aspect_changed && self.camera == self.home {
            self.reset_view();
        }
        self.pixel_ratio = if pixel_ratio.is_finite() && pixel_ratio > 0.0 {
            pixel_ratio
        } else {
            1.0
        };
    }

    /// Back to the home view ([`Camera::home`]) for the current field of view and aspect ratio.
    pub fn reset_view(&mut self) {
        let (pos1, pos2) = (self.cloud.pos1(), self.cloud.pos2());
        let framed = || {
            let shown = || self.shown_range(0, usize::MAX);
            shown().map(|i| pos1[i]).chain(shown().map(|i| pos2[i]))
        };
        self.home = Camera::home_of(framed, self.fov_y, self.viewport.aspect());
        self.camera = self.home;
    }

    /// Indices into the cloud of the drawn points `first..first + count` (clipped to the drawn
    /// points), ascending.
    fn shown_range(&self, first: usize, count: usize) -> impl Iterator<Item = usize> + '_ {
        let len = self.shown_len();
        let range = first.min(len)..first.saturating_add(count).min(len);
        let (all, some): (std::ops::Range<usize>, &[u32]) = match &self.shown {
            None => (range, &[]),
            Some(shown) => (0..0, &shown[range]),
        };
        all.chain(some.iter().map(|&i| i as usize))
    }

    /// A pointer went down at (`x`, `y`) CSS pixels from the canvas's top left; `drag` is what
    /// moving it alone does.
    pub fn pointer_down(&mut self, id: i32, x: f32, y: f32, drag: Drag) {
        self.controls.pointer_down(id, x, y, drag);
    }

    /// A pointer moved; returns whether the camera changed.
    pub fn pointer_move(&mut self, id: i32, x: f32, y: f32) -> bool {
        let height_css = self.viewport.height / self.pixel_ratio;
        self.controls
            .pointer_move(id, x, y, &mut self.camera, height_css, &self.bounds)
    }

    /// A pointer went up or was cancelled.
    pub fn pointer_up(&mut self, id: i32) {
        self.controls.pointer_up(id);
    }

    /// A wheel turn of `delta_y` CSS pixels (positive zooms out).
    pub fn wheel(&mut self, delta_y: f32) {
        self.controls.wheel(delta_y, &mut self.camera, &self.bounds);
    }

    /// The shader parameters for the current camera, viewport and settings.
    pub fn uniforms(&self) -> Uniforms {
        Uniforms {
            view_projection: self
                .camera
                .view_projection(self.viewport, &self.bounds)
                .to_cols_array(),
            viewport_px: [self.viewport.width, self.viewport.height],
            point_size_px: self.point_size * self.pixel_ratio,
            morph: self.morph,
        }
    }

    /// Number of points drawn.
    pub fn shown_len(&self) -> usize {
        self.shown.as_ref().map_or(self.cloud.len(), Vec::len)
    }

    /// Number of points in the cloud (before decimation).
    pub fn cloud_len(&self) -> usize {
        self.cloud.len()
    }

    /// The version of the drawn points' positions: it changes whenever they do.
    pub fn positions_version(&self) -> u64 {
        self.positions_version
    }

    /// The version of the drawn points' colours: it changes whenever they do.
    pub fn colours_version(&self) -> u64 {
        self.colours_version
    }

    /// Appends to `out` the packed positions of the drawn points `first..first + count`
    /// (clipped to the drawn points): two RGBA32F texels each, X then X', w = 1.
    pub fn pack_positions(&self, first: usize, count: usize, out: &mut Vec<[f32; 4]>) {
        let homogeneous = |[x, y, z]: [f32; 3]| [x, y, z, 1.0];
        let (pos1, pos2) = (self.cloud.pos1(), self.cloud.pos2());
        for i in self.shown_range(first, count) {
            out.extend([homogeneous(pos1[i]), homogeneous(pos2[i])]);
        }
    }

    /// Appends to `out` the packed colours of the drawn points `first..first + count` (clipped
    /// to the drawn points): frame-1 RGBA then frame-2 RGBA each, in the current colour mode.
    pub fn pack_colours(&self, first: usize, count: usize, out: &mut Vec<[u8; 4]>) {
        // The mode was checked against the cloud when it was set (set_cloud falls back to RGB
        // without labels); white is what a point would get otherwise.
        match Colouring::new(&self.cloud, self.colour_mode, self.depth_range) {
            Ok(colouring) => {
                let mark = self.flag_style == FlagStyle::Mark;
                for i in self.shown_range(first, count) {
                    if mark && self.is_flagged(i) {
                        out.extend([FLAG_COLOUR; 2]);
                    } else {
                        out.extend(colouring.pair(i));
                    }
                }
            }
            Err(_) => out.extend(self.shown_range(first, count).flat_map(|_| [[255; 4]; 2])),
        }
    }

    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    pub fn bounds(&self) -> &Bounds {
        &self.bounds
    }

    pub fn viewport(&self) -> Viewport {
        self.viewport
    }

    pub fn colour_mode(&self) -> ColourMode {
        self.colour_mode
    }

    pub fn morph(&self) -> f32 {
        self.morph
    }

    /// Point side length in CSS pixels.
    pub fn point_size(&self) -> f32 {
        self.point_size
    }

    pub fn point_budget(&self) -> usize {
        self.budget
    }

    pub fn background(&self) -> [u8; 3] {
        self.background
    }

    /// Re-selects the drawn points under the budget; their positions and colours change.
    fn select_points(&mut self) {
        let n = self.cloud.len();
        self.shown = if self.flag_style == FlagStyle::Hide && self.flagged.contains(&true) {
            let kept: Vec<u32> = (0..n)
                .filter(|&i| !self.is_flagged(i))
                .map(|i| i as u32)
                .collect();
            let chosen = decimate(kept.len(), self.budget);
            Some(if chosen.len() == kept.len() {
                kept
            } else {
                chosen.iter().map(|&k| kept[k as usize]).collect()
            })
        } else {
            (n > self.budget).then(|| decimate(n, self.budget))
        };
        self.positions_version += 1;
        self.colours_version += 1;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// All packed positions and colours of the drawn points.
    fn packed(view: &View) -> (Vec<[f32; 4]>, Vec<[u8; 4]>) {
        let (mut positions, mut colours) = (Vec::new(), Vec::new());
        view.pack_positions(0, usize::MAX, &mut positions);
        view.pack_colours(0, usize::MAX, &mut colours);
        (positions, colours)
    }

    #[test]
    fn a_camera_carries_over_to_another_view_of_the_same_cloud() {
        let mut one = View::default();
        one.set_cloud(two_point_cloud(None));
        one.set_viewport(400, 300, 1.0);
        one.pointer_down(1, 100.0, 100.0, Drag::Orbit);
        one.pointer_move(1, 160.0, 120.0);
        one.pointer_up(1);
        let mut two = View::default();
        two.set_cloud(two_point_cloud(None));
        two.set_viewport(400, 300, 1.0);
        assert_ne!(two.camera(), one.camera());
        two.set_camera(*one.camera());
        assert_eq!(two.camera(), one.camera());
        assert_eq!(two.uniforms().to_bytes(), one.uniforms().to_bytes());
    }

    fn two_point_cloud(labels: Option<&[u32]>) -> PointCloud {
        PointCloud::new(
            &[0.0, 0.0, 4.0, 1.0, 0.5, 6.0],
            Some(&[0.5, 0.0, 4.0, 1.0, 0.5, 6.0]),
            &[255, 0, 0, 0, 255, 0],
            labels,
        )
        .unwrap()
    }

    #[test]
    fn uniform_bytes_follow_the_wgsl_layout() {
        let u = Uniforms {
            view_projection: std::array::from_fn(|i| i as f32),
            viewport_px: [640.0, 480.0],
            point_size_px: 3.0,
            morph: 0.25,
        };
        let bytes = u.to_bytes();
        let float =
            |offset: usize| f32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap());
        assert_eq!(float(4 * 15), 15.0);
        assert_eq!((float(64), float(68)), (640.0, 480.0));
        assert_eq!((float(72), float(76)), (3.0, 0.25));
    }

    #[test]
    fn a_new_cloud_is_packed_and_viewed_from_camera_one() {
        let mut view = View::default();
        view.set_viewport(800, 600, 2.0);
        view.set_cloud(two_point_cloud(None));
        let (positions, colours) = packed(&view);
        assert_eq!(
            positions,
            [
                [0.0, 0.0, 4.0, 1.0],
                [0.5, 0.0, 4.0, 1.0],
                [1.0, 0.5, 6.0, 1.0],
                [1.0, 0.5, 6.0, 1.0]
            ]
        );
        assert!(view.positions_version() > 0);
        assert_eq!(colours.len(), 4);
        assert!(view.camera().eye().abs_diff_eq(Vec3::ZERO, 1e-4));
        let u = view.uniforms();
        assert_eq!(u.viewport_px, [800.0, 600.0]);
        assert_eq!(u.point_size_px, DEFAULT_POINT_SIZE * 2.0);
    }

    #[test]
    fn budget_decimates_and_bumps_the_versions() {
        let n = 1000;
        let pos: Vec<f32> = (0..n).flat_map(|i| [i as f32, 0.0, 10.0]).collect();
        let cloud = PointCloud::new(&pos, None, &vec![9; 3 * n], None).unwrap();
        let mut view = View::new(100);
        view.set_cloud(cloud);
        assert_eq!((view.shown_len(), view.cloud_len()), (100, 1000));
        let before = view.positions_version();
        view.set_point_budget(400);
        assert_eq!(view.shown_len(), 400);
        let (positions, colours) = packed(&view);
        assert_eq!(positions.len(), 400 * 2);
        assert_eq!(colours.len(), 400 * 2);
        assert!(view.positions_version() > before);
        // Packing in slices gives the same as packing at once.
        let mut sliced = Vec::new();
        for first in (0..400).step_by(64) {
            view.pack_positions(first, 64, &mut sliced);
        }
        assert_eq!(sliced, positions);
    }

    #[test]
    fn flagged_superpixels_are_marked_or_hidden() {
        let mut view = View::default();
        view.set_cloud(two_point_cloud(Some(&[3, 4])));
        view.set_flagged(&[4], FlagStyle::Mark).unwrap();
        let (_, colours) = packed(&view);
        assert_eq!(
            colours,
            [[255, 0, 0, 255], [255, 0, 0, 255], FLAG_COLOUR, FLAG_COLOUR]
        );
        view.set_flagged(&[4], FlagStyle::Hide).unwrap();
        assert_eq!((view.shown_len(), view.cloud_len()), (1, 2));
        assert_eq!(
            packed(&view).0,
            [[0.0, 0.0, 4.0, 1.0], [0.5, 0.0, 4.0, 1.0]]
        );
        // The flags stay for the next cloud; a cloud without labels has nothing flagged.
        view.set_cloud(two_point_cloud(Some(&[4, 4])));
        assert_eq!(view.shown_len(), 0);
        view.set_cloud(two_point_cloud(None));
        assert_eq!(view.shown_len(), 2);
        view.set_flagged(&[], FlagStyle::Hide).unwrap();
        assert!(view.set_flagged(&[u32::MAX], FlagStyle::Hide).is_err());
        view.set_cloud(two_point_cloud(Some(&[3, 4])));
        assert_eq!(view.shown_len(), 2);
        assert!("blink".parse::<FlagStyle>().is_err());
    }

    #[test]
    fn settings_are_checked() {
        let mut view = View::default();
        view.set_cloud(two_point_cloud(None));
        assert!(view.set_morph(0.5).is_ok());
        assert!(view.set_morph(1.5).is_err());
        assert!(view.set_morph(f32::NAN).is_err());
        assert_eq!(view.morph(), 0.5);
        view.set_frame(2).unwrap();
        assert_eq!(view.morph(), 1.0);
        assert!(view.set_frame(3).is_err());
        assert!(view.set_point_size(0.0).is_err());
        view.set_point_size(500.0).unwrap();
        assert_eq!(view.point_size(), MAX_POINT_SIZE);
        assert!(view.set_field_of_view(180.0).is_err());
        assert!(view.set_colour_mode(ColourMode::Superpixel).is_err());
        assert_eq!(view.colour_mode(), ColourMode::Rgb);
    }

    #[test]
    fn superpixel_mode_falls_back_to_rgb_for_a_cloud_without_labels() {
        let mut view = View::default();
        view.set_cloud(two_point_cloud(Some(&[3, 4])));
        view.set_colour_mode(ColourMode::Superpixel).unwrap();
        view.set_cloud(two_point_cloud(None));
        assert_eq!(view.colour_mode(), ColourMode::Rgb);
        assert_eq!(packed(&view).1[0], [255, 0, 0, 255]);
    }

    #[test]
    fn taking_the_cloud_out_keeps_the_colour_mode_for_the_next() {
        let mut view = View::default();
        view.set_cloud(two_point_cloud(Some(&[3, 4])));
        view.set_colour_mode(ColourMode::Superpixel).unwrap();
        let old = view.take_cloud();
        assert_eq!((old.len(), view.cloud_len()), (2, 0));
        view.set_cloud(two_point_cloud(Some(&[3, 4])));
        assert_eq!(view.colour_mode(), ColourMode::Superpixel);
    }

    #[test]
    fn a_new_aspect_reframes_the_home_view_until_the_user_moves() {
        let mut view = View::default();
        view.set_field_of_view(30.0).unwrap();
        view.set_viewport(400, 400, 1.0);
        // A cloud wider than the square view at camera 1: the home view backs off.
        let cloud = PointCloud::new(&[-3.0, 0.0, 5.0, 3.0, 0.0, 5.0], None, &[0; 6], None).unwrap();
        view.set_cloud(cloud);
        let square = view.camera().distance;
        view.set_viewport(1600, 400, 1.0);
        assert!(
            view.camera().distance < square,
            "a wider view needs less distance"
        );
        view.wheel(50.0);
        let moved = *view.camera();
        view.set_viewport(400, 400, 1.0);
        assert_eq!(*view.camera(), moved);
    }

    #[test]
    fn gestures_move_the_camera_and_reset_brings_it_home() {
        let mut view = View::default();
        view.set_viewport(400, 300, 1.0);
        view.set_cloud(two_point_cloud(None));
        let home = *view.camera();
        view.pointer_down(1, 10.0, 10.0, Drag::Orbit);
        assert!(view.pointer_move(1, 60.0, 30.0));
        view.pointer_up(1);
        view.wheel(120.0);
        assert_ne!(*view.camera(), home);
        view.reset_view();
        assert_eq!(*view.camera(), home);
    }
}
