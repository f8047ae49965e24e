//! The 3D point-cloud viewer for JavaScript: a thin wrapper of [`crate::render`] that owns a
//! canvas, listens to its pointer, wheel and resize events, and redraws on the next animation
//! frame whenever something changed.
//!
//! ```js
//! import init, { Viewer } from './pkg/superpixel_soup.js';
//! await init();
//! const viewer = await Viewer.create(canvas, { backend: 'auto' }); // rejects: a readable Error
//! viewer.backend;                                   // "webgpu" or "webgl2"
//! viewer.setCloud(pos1, pos2, rgb, labels);         // Float32Array ×2, Uint8Array, Uint32Array?
//! viewer.setMorph(0.5);                             // or viewer.setFrame(2)
//! const png = await viewer.screenshot();            // Uint8Array, PNG bytes
//! viewer.free();
//! ```
//!
//! Conventions: positions are x, y, z per point in camera 1's OpenCV frame (x right, y down,
//! z forward; any length unit); colours are sRGB bytes r, g, b per point; sizes are CSS pixels.
//! Controls (attached by the viewer itself unless `controls: false`): drag with the primary
//! button or one finger orbits, drag with the secondary or middle button, or with Shift, Ctrl or
//! Meta held, pans; two fingers pinch to zoom and move together to pan; the wheel zooms;
//! double-click resets the view. With `controls: false` the page forwards events itself
//! through `pointerDown` / `pointerMove` / `pointerUp` / `wheel`.

use std::cell::RefCell;
use std::rc::{Rc, Weak};

use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;
use web_sys::{
    AddEventListenerOptions, Event, EventTarget, HtmlCanvasElement, PointerEvent, ResizeObserver,
    WheelEvent,
};

use crate::image::encode_png;
use crate::render::RenderError;
use crate::render::cloud::PointCloud;
use crate::render::colour::ColourMode;
use crate::render::controls::Drag;
use crate::render::decimate::{DESKTOP_POINT_BUDGET, MOBILE_POINT_BUDGET};
use crate::render::gpu::{BackendChoice, Gpu};
use crate::render::view::{FlagStyle, View};

/// What the viewer owns besides its event listeners: the state, the GPU and the canvas.
struct Inner {
    view: View,
    gpu: Gpu,
    canvas: HtmlCanvasElement,
    /// The pending `requestAnimationFrame` id, if a redraw is scheduled.
    frame_request: Option<i32>,
    /// The animation-frame callback (kept alive here; it holds only a weak reference back).
    on_frame: Option<Closure<dyn FnMut()>>,
}

impl Inner {
    /// Matches the drawing buffer to the canvas's displayed size × devicePixelRatio (a canvas
    /// that is not laid out keeps its width and height attributes), then draws.
    fn draw_now(&mut self) {
        self.sync_size();
        self.gpu.render(&self.view);
    }

    fn sync_size(&mut self) {
        let ratio = web_sys::window().map_or(1.0, |w| w.device_pixel_ratio());
        let (css_w, css_h) = (self.canvas.client_width(), self.canvas.client_height());
        let (width, height, ratio) = if css_w > 0 && css_h > 0 {
            let scale = |css: i32| (css as f64 * ratio).round() as u32;
            (scale(css_w), scale(css_h), ratio)
        } else {
            (self.canvas.width(), self.canvas.height(), 1.0)
        };
        let max = self.gpu.max_size();
        let (width, height) = (width.clamp(1, max), height.clamp(1, max));
        if self.canvas.width() != width {
            self.canvas.set_width(width);
        }
        if self.canvas.height() != height {
            self.canvas.set_height(height);
        }
        self.gpu.resize(width, height);
        self.view.set_viewport(width, height, ratio as f32);
    }

    /// Schedules a redraw on the next animation frame (once, however often it is asked).
    fn request_frame(&mut self) {
        if self.frame_request.is_some() {
            return;
        }
        let (Some(window), Some(callback)) = (web_sys::window(), self.on_frame.as_ref()) else {
            return;
        };
        self.frame_request = window
            .request_animation_frame(callback.as_ref().unchecked_ref())
            .ok();
    }
}

/// An event listener that removes itself when dropped.
struct Listener {
    target: EventTarget,
    kind: &'static str,
    callback: Closure<dyn FnMut(Event)>,
}

impl Drop for Listener {
    fn drop(&mut self) {
        let _ = self
            .target
            .remove_event_listener_with_callback(self.kind, self.callback.as_ref().unchecked_ref());
    }
}

/// The 3D point-cloud viewer on one canvas.
#[wasm_bindgen]
pub struct Viewer {
    inner: Rc<RefCell<Inner>>,
    listeners: Vec<Listener>,
    resize_observer: Option<(ResizeObserver, Closure<dyn FnMut()>)>,
}

#[wasm_bindgen]
impl Viewer {
    /// Opens the viewer on `canvas`. Options (all optional):
    /// - `backend`: `"auto"` (default: WebGPU when it works, else WebGL2), `"webgpu"` or
    ///   `"webgl2"`;
    /// - `pointBudget`: most points drawn (default 1 048 576, or 300 000 on a touch-first device);
    /// - `fieldOfView`: vertical field of view in degrees (default 50; see `setFieldOfView`);
    /// - `controls`: attach pointer, wheel and double-click listeners (default `true`).
    ///
    /// Rejects with an `Error` whose message says why no backend works; the page should show
    /// it instead of the canvas.
    pub async fn create(
        canvas: HtmlCanvasElement,
        options: Option<js_sys::Object>,
    ) -> Result<Viewer, JsError> {
        let options = Options::read(options.as_ref())?;
        let gpu = Gpu::open(&canvas, options.backend).await?;
        let mut view = View::new(options.point_budget.min(gpu.max_points()));
        if let Some(degrees) = options.field_of_view {
            view.set_field_of_view(degrees)?;
        }
        let inner = Rc::new(RefCell::new(Inner {
            view,
            gpu,
            canvas: canvas.clone(),
            frame_request: None,
            on_frame: None,
        }));
        let weak = Rc::downgrade(&inner);
        inner.borrow_mut().on_frame = Some(Closure::new(move || {
            if let Some(inner) = weak.upgrade()
                && let Ok(mut inner) = inner.try_borrow_mut()
            {
                inner.frame_request = None;
                inner.draw_now();
            }
        }));
        let mut viewer = Viewer {
            inner,
            listeners: Vec::new(),
            resize_observer: None,
        };
        viewer.observe_resizes();
        let weak = Rc::downgrade(&viewer.inner);
        let target: EventTarget = canvas.clone().into();
        viewer.listen(&target, "webglcontextlost", &weak, |inner, _| {
            inner.gpu.mark_lost()
        });
        if options.controls {
            viewer.attach_controls(&canvas);
        }
        viewer.inner.borrow_mut().request_frame();
        Ok(viewer)
    }

    /// The backend in use: `"webgpu"` or `"webgl2"`.
    #[wasm_bindgen(getter)]
    pub fn backend(&self) -> String {
        self.inner.borrow().gpu.backend().name().to_string()
    }

    /// The GPU adapter's name as the browser reports it (often empty: browsers hide it).
    #[wasm_bindgen(getter, js_name = adapterName)]
    pub fn adapter_name(&self) -> String {
        self.inner.borrow().gpu.adapter_name().to_string()
    }

    /// Shows a cloud from the home view (through camera 1, framed on the cloud).
    /// `pos1`: x, y, z per point (frame 1, camera 1's OpenCV frame), a `Float32Array`; `pos2`:
    /// the same points in frame 2 (same frame of reference), or `null`/`undefined` for a still
    /// cloud; `rgb`: r, g, b bytes per point, a `Uint8Array`; `labels`: a superpixel id per
    /// point, a `Uint32Array`, or `null`/`undefined`. Plain arrays of numbers are taken too.
    /// Points with a non-finite coordinate are left out. The buffers are read a slice at a time
    /// (never copied whole into wasm memory), and the previous cloud is freed before the new
    /// one is built, so the viewer holds one cloud (31 bytes per point) at a time. Throws when
    /// the lengths disagree or a buffer is of the wrong kind (the previous cloud stays then).
    #[wasm_bindgen(js_name = setCloud)]
    pub fn set_cloud(
        &self,
        pos1: &JsValue,
        pos2: &JsValue,
        rgb: &JsValue,
        labels: &JsValue,
    ) -> Result<(), JsError> {
        let absent = |v: &JsValue| v.is_null() || v.is_undefined();
        let pos1 = typed(
            pos1,
            "frame-1 positions",
            "Float32Array",
            js_sys::Float32Array::new,
        )?;
        let pos2 = (!absent(pos2))
            .then(|| {
                typed(
                    pos2,
                    "frame-2 positions",
                    "Float32Array",
                    js_sys::Float32Array::new,
                )
            })
            .transpose()?;
        let rgb = typed(rgb, "colours", "Uint8Array", js_sys::Uint8Array::new)?;
        let labels = (!absent(labels))
            .then(|| typed(labels, "labels", "Uint32Array", js_sys::Uint32Array::new))
            .transpose()?;
        let n = PointCloud::check_lengths(
            pos1.length() as usize,
            pos2.as_ref().map(|a| a.length() as usize),
            rgb.length() as usize,
            labels.as_ref().map(|a| a.length() as usize),
        )?;
        let old = self.inner.borrow_mut().view.take_cloud();
        drop(old);
        let mut cloud = PointCloud::with_capacity(n, labels.is_some());
        let (mut p1, mut p2, mut c, mut l) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for first in (0..n).step_by(CLOUD_SLICE) {
            let end = (first + CLOUD_SLICE).min(n);
            let read_f32 = |array: &js_sys::Float32Array, out: &mut Vec<f32>| {
                out.resize(3 * (end - first), 0.0);
                array
                    .subarray(3 * first as u32, 3 * end as u32)
                    .copy_to(out);
            };
            read_f32(&pos1, &mut p1);
            if let Some(pos2) = &pos2 {
                read_f32(pos2, &mut p2);
            }
            c.resize(3 * (end - first), 0);
            rgb.subarray(3 * first as u32, 3 * end as u32)
                .copy_to(&mut c);
            if let Some(labels) = &labels {
                l.resize(end - first, 0);
                labels.subarray(first as u32, end as u32).copy_to(&mut l);
            }
            cloud.extend(
                &p1,
                pos2.is_some().then_some(&p2[..]),
                &c,
                labels.is_some().then_some(&l[..]),
            )?;
        }
        self.update(|view| {
            view.set_cloud(cloud);
            Ok(())
        })
    }

    /// Flags the points of the superpixels `labels` (a `Uint32Array` or an array of numbers; the
    /// page flags those whose depth is a guess) and shows them as `style` says: `"show"` (like
    /// the others), `"mark"` (magenta, whatever the colour mode) or `"hide"` (not drawn:
    /// `shownPointCount` drops). The flags stay for later clouds of the same labels. Throws for
    /// another style or a label of 2²⁴ or more.
    #[wasm_bindgen(js_name = setFlagged)]
    pub fn set_flagged(&self, labels: Vec<u32>, style: &str) -> Result<(), JsError> {
        let style: FlagStyle = style.parse()?;
        self.update(|view| view.set_flagged(&labels, style))
    }

    /// Morph parameter t in [0, 1]: points are drawn at X + t·(X' − X), so 0 is frame 1, 1 is
    /// frame 2. Throws outside [0, 1].
    #[wasm_bindgen(js_name = setMorph)]
    pub fn set_morph(&self, t: f32) -> Result<(), JsError> {
        self.update(|view| view.set_morph(t))
    }

    /// Shows frame 1 or 2 (the same as `setMorph(0)` / `setMorph(1)`). Throws for other values.
    #[wasm_bindgen(js_name = setFrame)]
    pub fn set_frame(&self, frame: u32) -> Result<(), JsError> {
        self.update(|view| view.set_frame(frame))
    }

    /// The current morph parameter (0 = frame 1, 1 = frame 2).
    #[wasm_bindgen(getter)]
    pub fn morph(&self) -> f32 {
        self.inner.borrow().view.morph()
    }

    /// Point side length in CSS pixels (default 2), clamped to [1, 64]. Throws for values ≤ 0.
    #[wasm_bindgen(js_name = setPointSize)]
    pub fn set_point_size(&self, css_pixels: f32) -> Result<(), JsError> {
        self.update(|view| view.set_point_size(css_pixels))
    }

    /// `"rgb"` (photo colours), `"depth"` (Turbo colour map of depth in camera 1: near red, far
    /// blue; the same colours as the depth pictures) or `"superpixel"` (a colour per label; needs
    /// labels). Throws for other names and for `"superpixel"` without labels. A new cloud without
    /// labels switches `"superpixel"` back to `"rgb"`.
    #[wasm_bindgen(js_name = setColourMode)]
    pub fn set_colour_mode(&self, mode: &str) -> Result<(), JsError> {
        let mode: ColourMode = mode.parse()?;
        self.update(|view| view.set_colour_mode(mode))
    }

    /// The current colour mode's name.
    #[wasm_bindgen(getter, js_name = colourMode)]
    pub fn colour_mode(&self) -> String {
        self.inner.borrow().view.colour_mode().name().to_string()
    }

    /// Draws at most `budget` points (≥ 1); larger clouds are decimated deterministically
    /// (the same points every time). Capped by what the GPU's buffers hold.
    #[wasm_bindgen(js_name = setPointBudget)]
    pub fn set_point_budget(&self, budget: u32) -> Result<(), JsError> {
        let max = self.inner.borrow().gpu.max_points();
        self.update(|view| {
            view.set_point_budget((budget as usize).min(max));
            Ok(())
        })
    }

    /// Number of points in the cloud (after leaving out non-finite ones).
    #[wasm_bindgen(getter, js_name = pointCount)]
    pub fn point_count(&self) -> u32 {
        self.inner.borrow().view.cloud_len() as u32
    }

    /// Number of points drawn (after decimation).
    #[wasm_bindgen(getter, js_name = shownPointCount)]
    pub fn shown_point_count(&self) -> u32 {
        self.inner.borrow().view.shown_len() as u32
    }

    /// Vertical field of view in degrees, in (0, 180). To look exactly through camera 1, use
    /// 2·atan(H / (2·fy)) for a photo H pixels tall with focal length fy pixels, and a canvas of
    /// the photo's aspect ratio (the principal point is taken as the image centre). Resets the
    /// view. Throws outside (0, 180).
    #[wasm_bindgen(js_name = setFieldOfView)]
    pub fn set_field_of_view(&self, degrees: f32) -> Result<(), JsError> {
        self.update(|view| {
            view.set_field_of_view(degrees)?;
            view.reset_view();
            Ok(())
        })
    }

    /// Background colour, sRGB bytes (default #1d2330).
    #[wasm_bindgen(js_name = setBackground)]
    pub fn set_background(&self, r: u8, g: u8, b: u8) -> Result<(), JsError> {
        self.update(|view| {
            view.set_background([r, g, b]);
            Ok(())
        })
    }

    /// Back to the home view: looking along camera 1's optical axis, from camera 1's centre
    /// when the cloud fits the view, else from farther back on the axis.
    #[wasm_bindgen(js_name = resetView)]
    pub fn reset_view(&self) -> Result<(), JsError> {
        self.update(|view| {
            view.reset_view();
            Ok(())
        })
    }

    /// For pages that handle events themselves (`controls: false`): a pointer went down at
    /// (`x`, `y`) CSS pixels from the canvas's top-left corner; `pan` chooses panning instead of
    /// orbiting for a one-pointer drag.
    #[wasm_bindgen(js_name = pointerDown)]
    pub fn pointer_down(&self, id: i32, x: f32, y: f32, pan: bool) {
        let drag = if pan { Drag::Pan } else { Drag::Orbit };
        self.inner.borrow_mut().view.pointer_down(id, x, y, drag);
    }

    /// A pointer moved to (`x`, `y`) CSS pixels; redraws when the camera moved.
    #[wasm_bindgen(js_name = pointerMove)]
    pub fn pointer_move(&self, id: i32, x: f32, y: f32) {
        let mut inner = self.inner.borrow_mut();
        if inner.view.pointer_move(id, x, y) {
            inner.request_frame();
        }
    }

    /// A pointer went up or was cancelled.
    #[wasm_bindgen(js_name = pointerUp)]
    pub fn pointer_up(&self, id: i32) {
        self.inner.borrow_mut().view.pointer_up(id);
    }

    /// A wheel turn of `delta_y` CSS pixels (positive zooms out).
    pub fn wheel(&self, delta_y: f32) {
        let mut inner = self.inner.borrow_mut();
        inner.view.wheel(delta_y);
        inner.request_frame();
    }

    /// The camera as `[targetX, targetY, targetZ, distance, yaw, pitch]` (radians), for
    /// [`setCamera`](Viewer::set_camera) on another viewer of the same cloud (e.g. after the GPU
    /// was lost).
    #[wasm_bindgen(getter)]
    pub fn camera(&self) -> Vec<f32> {
        let c = *self.inner.borrow().view.camera();
        vec![
            c.target.x, c.target.y, c.target.z, c.distance, c.yaw, c.pitch,
        ]
    }

    /// Puts the camera where [`camera`](Viewer::camera) said (six numbers); call it after
    /// `setCloud`, which resets the view.
    #[wasm_bindgen(js_name = setCamera)]
    pub fn set_camera(&self, camera: &[f32]) -> Result<(), JsError> {
        let &[x, y, z, distance, yaw, pitch] = camera else {
            return Err(JsError::new(
                "a camera is six numbers: target x, y, z, distance, yaw, pitch",
            ));
        };
        if camera.iter().any(|v| !v.is_finite()) || distance <= 0.0 {
            return Err(JsError::new(
                "a camera needs finite numbers and a positive distance",
            ));
        }
        self.update(|view| {
            let mut c = *view.camera();
            c.target = glam::Vec3::new(x, y, z);
            c.distance = distance;
            c.yaw = yaw;
            c.pitch = pitch;
            view.set_camera(c);
            Ok(())
        })
    }

    /// True once the GPU device (WebGPU) or the context (WebGL2) is lost: this viewer draws
    /// nothing more, and the page should open a new one (the event `viewerlost` on `window`,
    /// or `webglcontextlost` on the canvas, says when).
    #[wasm_bindgen(getter)]
    pub fn lost(&self) -> bool {
        self.inner.borrow().gpu.is_lost()
    }

    /// Draws now (the viewer otherwise redraws by itself on the next animation frame after
    /// each change). Resizes the drawing buffer to the canvas's CSS size × devicePixelRatio.
    pub fn render(&self) {
        self.inner.borrow_mut().draw_now();
    }

    /// The current view as PNG bytes (RGB, the drawing buffer's size), rendered off screen.
    #[wasm_bindgen(js_name = screenshot, unchecked_return_type = "Promise<Uint8Array>")]
    pub fn screenshot(&self) -> js_sys::Promise {
        if self.lost() {
            return js_sys::Promise::reject(
                &JsError::new("the 3D view's GPU was lost; open a new viewer").into(),
            );
        }
        let pending = {
            let mut inner = self.inner.borrow_mut();
            inner.sync_size();
            let Inner { gpu, view, .. } = &mut *inner;
            gpu.read_pixels(view)
        };
        wasm_bindgen_futures::future_to_promise(async move {
            let frame = pending.pixels().await.map_err(to_js)?;
            let png = encode_png(&frame).map_err(to_js)?;
            Ok(js_sys::Uint8Array::from(png.as_slice()).into())
        })
    }

    /// Resolves once the GPU has finished everything drawn so far (for timing).
    #[wasm_bindgen(unchecked_return_type = "Promise<void>")]
    pub fn finish(&self) -> js_sys::Promise {
        let pending = self.inner.borrow().gpu.finish();
        wasm_bindgen_futures::future_to_promise(async move {
            pending.wait().await.map_err(to_js)?;
            Ok(JsValue::UNDEFINED)
        })
    }
}

impl Viewer {
    /// Applies `change` to the view and schedules a redraw.
    fn update(
        &self,
        change: impl FnOnce(&mut View) -> crate::render::Result<()>,
    ) -> Result<(), JsError> {
        let mut inner = self.inner.borrow_mut();
        change(&mut inner.view)?;
        inner.request_frame();
        Ok(())
    }

    /// Redraws when the canvas's displayed size changes.
    fn observe_resizes(&mut self) {
        let weak = Rc::downgrade(&self.inner);
        let callback: Closure<dyn FnMut()> = Closure::new(move || {
            if let Some(inner) = weak.upgrade()
                && let Ok(mut inner) = inner.try_borrow_mut()
            {
                inner.request_frame();
            }
        });
        if let Ok(observer) = ResizeObserver::new(callback.as_ref().unchecked_ref()) {
            observer.observe(&self.inner.borrow().canvas);
            self.resize_observer = Some((observer, callback));
        }
    }

    /// Pointer, wheel, double-click and context-menu listeners on the canvas.
    fn attach_controls(&mut self, canvas: &HtmlCanvasElement) {
        // Touch gestures belong to the viewer, not to page scrolling and zooming.
        let _ = canvas.style().set_property("touch-action", "none");
        let target: EventTarget = canvas.clone().into();
        let weak = Rc::downgrade(&self.inner);

        self.listen(&target, "pointerdown", &weak, |inner, event| {
            let Some(e) = event.dyn_ref::<PointerEvent>() else {
                return;
            };
            let (x, y) = canvas_position(&inner.canvas, e.client_x(), e.client_y());
            let pan =
                e.button() == 1 || e.button() == 2 || e.shift_key() || e.ctrl_key() || e.meta_key();
            let drag = if pan { Drag::Pan } else { Drag::Orbit };
            inner.view.pointer_down(e.pointer_id(), x, y, drag);
            let _ = inner.canvas.set_pointer_capture(e.pointer_id());
        });
        self.listen(&target, "pointermove", &weak, |inner, event| {
            let Some(e) = event.dyn_ref::<PointerEvent>() else {
                return;
            };
            let (x, y) = canvas_position(&inner.canvas, e.client_x(), e.client_y());
            if inner.view.pointer_move(e.pointer_id(), x, y) {
                inner.request_frame();
            }
        });
        for kind in ["pointerup", "pointercancel"] {
            self.listen(&target, kind, &weak, |inner, event| {
                if let Some(e) = event.dyn_ref::<PointerEvent>() {
                    inner.view.pointer_up(e.pointer_id());
                }
            });
        }
        self.listen(&target, "wheel", &weak, |inner, event| {
            let Some(e) = event.dyn_ref::<WheelEvent>() else {
                return;
            };
            event.prevent_default();
            // deltaMode: 0 pixels, 1 lines, 2 pages.
            let scale = match e.delta_mode() {
                1 => 16.0,
                2 => 400.0,
                _ => 1.0,
            };
            inner.view.wheel((e.delta_y() * scale) as f32);
            inner.request_frame();
        });
        self.listen(&target, "dblclick", &weak, |inner, _| {
            inner.view.reset_view();
            inner.request_frame();
        });
        self.listen(&target, "contextmenu", &weak, |_, event| {
            event.prevent_default()
        });
    }

    /// Adds a listener for `kind` on `target` that runs `handle` on the viewer's state (skipped
    /// if the viewer is gone or busy). Not passive, so handlers may call `preventDefault`.
    fn listen(
        &mut self,
        target: &EventTarget,
        kind: &'static str,
        weak: &Weak<RefCell<Inner>>,
        handle: impl Fn(&mut Inner, &Event) + 'static,
    ) {
        let weak = weak.clone();
        let callback: Closure<dyn FnMut(Event)> = Closure::new(move |event: Event| {
            if let Some(inner) = weak.upgrade()
                && let Ok(mut inner) = inner.try_borrow_mut()
            {
                handle(&mut inner, &event);
            }
        });
        let options = AddEventListenerOptions::new();
        options.set_passive(false);
        if target
            .add_event_listener_with_callback_and_add_event_listener_options(
                kind,
                callback.as_ref().unchecked_ref(),
                &options,
            )
            .is_ok()
        {
            self.listeners.push(Listener {
                target: target.clone(),
                kind,
                callback,
            });
        }
    }
}

impl Drop for Viewer {
    /// Detaches every listener and cancels a scheduled redraw, so nothing calls into the freed
    /// viewer.
    fn drop(&mut self) {
        self.listeners.clear();
        if let Some((observer, _)) = &self.resize_observer {
            observer.disconnect();
        }
        if let Ok(mut inner) = self.inner.try_borrow_mut()
            && let Some(id) = inner.frame_request.take()
            && let Some(window) = web_sys::window()
        {
            let _ = window.cancel_animation_frame(id);
        }
    }
}

/// Client (viewport) coordinates → CSS pixels from the canvas's top-left corner.
fn canvas_position(canvas: &HtmlCanvasElement, client_x: i32, client_y: i32) -> (f32, f32) {
    let rect = canvas.get_bounding_client_rect();
    (
        (client_x as f64 - rect.left()) as f32,
        (client_y as f64 - rect.top()) as f32,
    )
}

/// The options of [`Viewer::create`].
struct Options {
    backend: BackendChoice,
    point_budget: usize,
    field_of_view: Option<f32>,
    controls: bool,
}

impl Options {
    fn read(options: Option<&js_sys::Object>) -> crate::render::Result<Options> {
        let get = |name: &str| {
            options
                .and_then(|o| js_sys::Reflect::get(o, &name.into()).ok())
                .filter(|v| !v.is_undefined() && !v.is_null())
        };
        let bad = |what: &str| RenderError::InvalidParameter(format!("viewer option {what}"));
        let backend = match get("backend") {
            None => BackendChoice::Auto,
            Some(v) => v
                .as_string()
                .ok_or_else(|| bad("backend must be a string"))?
                .parse()?,
        };
        let point_budget = match get("pointBudget") {
            None => default_point_budget(),
            Some(v) => match v.as_f64() {
                Some(n) if n >= 1.0 => n as usize,
                _ => return Err(bad("pointBudget must be a number ≥ 1")),
            },
        };
        let field_of_view = match get("fieldOfView") {
            None => None,
            Some(v) => Some(
                v.as_f64()
                    .ok_or_else(|| bad("fieldOfView must be a number"))? as f32,
            ),
        };
        let controls = match get("controls") {
            None => true,
            Some(v) => v
                .as_bool()
                .ok_or_else(|| bad("controls must be true or false"))?,
        };
        Ok(Options {
            backend,
            point_budget,
            field_of_view,
            controls,
        })
    }
}

/// The smaller mobile budget where the primary pointer is coarse (a finger), else the desktop one.
fn default_point_budget() -> usize {
    let coarse = web_sys::window()
        .and_then(|w| w.match_media("(pointer: coarse)").ok().flatten())
        .is_some_and(|m| m.matches());
    if coarse {
        MOBILE_POINT_BUDGET
    } else {
        DESKTOP_POINT_BUDGET
    }
}

/// Points read from JavaScript's buffers at a time by [`Viewer::set_cloud`] (64 Ki points:
/// 1.9 MiB of scratch).
const CLOUD_SLICE: usize = 1 << 16;

/// `value` as a typed array of kind `T` (`kind` names it): the array itself, or a copy of a plain
/// JavaScript array made by `copy` (the typed array's constructor); an error naming the buffer
/// (`what`) for anything else.
fn typed<T: JsCast + Clone>(
    value: &JsValue,
    what: &str,
    kind: &str,
    copy: impl FnOnce(&JsValue) -> T,
) -> Result<T, RenderError> {
    if let Some(array) = value.dyn_ref::<T>() {
        Ok(array.clone())
    } else if js_sys::Array::is_array(value) {
        Ok(copy(value))
    } else {
        Err(RenderError::InvalidParameter(format!(
            "point cloud: {what} must be a {kind} (or an array of numbers)"
        )))
    }
}

fn to_js(error: impl std::error::Error) -> JsValue {
    JsError::from(error).into()
}
