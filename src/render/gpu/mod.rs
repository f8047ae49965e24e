//! The viewer's GPU part (wasm only): opens WebGPU or WebGL2 through wgpu on a canvas, draws the
//! [`View`] there, and reads rendered frames back for screenshots.
//!
//! Backend choice: WebGPU when `navigator.gpu` hands out an adapter and a device, else WebGL2
//! (wgpu's GL backend). The WebGPU attempt touches the canvas only once it has a device, so a
//! failed attempt leaves the canvas free for a WebGL2 context.
//!
//! The canvas is configured with a non-sRGB format where the backend offers one (WebGPU and
//! WebGL2 both do), so sRGB colour bytes reach the screen unchanged; on an sRGB-only surface the
//! shader linearises them first (`fs_srgb`).

mod points;
mod readback;

use std::str::FromStr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use wasm_bindgen::JsCast;
use wasm_bindgen_futures::JsFuture;
use web_sys::HtmlCanvasElement;

use crate::render::{RenderError, Result};

use super::view::View;
use points::PointPass;
pub use readback::{PendingPicture, PendingWork};

/// The event dispatched on `window` when a viewer's GPU device is lost (WebGPU); a lost WebGL2
/// context fires `webglcontextlost` on the canvas instead.
pub const LOST_EVENT: &str = "viewerlost";

/// The graphics API in use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    WebGpu,
    WebGl2,
}

impl Backend {
    /// `"webgpu"` or `"webgl2"`, as the JavaScript API reports it.
    pub fn name(self) -> &'static str {
        match self {
            Backend::WebGpu => "webgpu",
            Backend::WebGl2 => "webgl2",
        }
    }
}

/// Which backend to open.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BackendChoice {
    /// WebGPU if it works, else WebGL2.
    #[default]
    Auto,
    /// WebGPU only (fails without it).
    WebGpu,
    /// WebGL2 only, even where WebGPU works.
    WebGl2,
}

impl FromStr for BackendChoice {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(BackendChoice::Auto),
            "webgpu" => Ok(BackendChoice::WebGpu),
            "webgl2" => Ok(BackendChoice::WebGl2),
            other => Err(RenderError::InvalidParameter(format!(
                "backend must be \"auto\", \"webgpu\" or \"webgl2\", not {other:?}"
            ))),
        }
    }
}

/// A wgpu device drawing into one canvas.
pub struct Gpu {
    backend: Backend,
    adapter_name: String,
    device: wgpu::Device,
    queue: wgpu::Queue,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    points: PointPass,
    /// Set once the device is lost (WebGPU's `device.lost`, or the WebGL2 context lost): the
    /// page must open a new viewer; this one draws nothing more.
    lost: Arc<AtomicBool>,
    // Kept alive for the surface's sake.
    _instance: wgpu::Instance,
}

impl Gpu {
    /// Opens a backend on `canvas` as `choice` says. The error names every backend tried and
    /// why it failed.
    pub async fn open(canvas: &HtmlCanvasElement, choice: BackendChoice) -> Result<Gpu> {
        let mut failures = Vec::new();
        if choice != BackendChoice::WebGl2 {
            match open_webgpu(canvas).await {
                Ok(gpu) => return Ok(gpu),
                Err(reason) => failures.push(format!("WebGPU: {reason}")),
            }
        }
        if choice != BackendChoice::WebGpu {
            match open_webgl2(canvas).await {
                Ok(gpu) => return Ok(gpu),
                Err(reason) => failures.push(format!("WebGL2: {reason}")),
            }
        }
        Err(RenderError::Graphics(format!(
            "this browser cannot show the 3D view ({})",
            failures.join("; ")
        )))
    }

    /// The backend in use.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The adapter's name as the browser reports it (may be empty: browsers hide it).
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// Whether the device or context is lost (see [`Gpu::mark_lost`]).
    pub fn is_lost(&self) -> bool {
        self.lost.load(Ordering::Relaxed)
    }

    /// Records that the device or context is lost (the WebGL2 canvas said so); nothing is
    /// drawn or read back from then on.
    pub fn mark_lost(&self) {
        self.lost.store(true, Ordering::Relaxed);
    }

    /// Largest width or height of the drawing buffer this device can render.
    pub fn max_size(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Most points whose buffers fit this device.
    pub fn max_points(&self) -> usize {
        points::max_points(&self.device)
    }

    /// Resizes the canvas's surface to `width` × `height` pixels (clamped to [1, max_size]);
    /// does nothing when the size is unchanged.
    pub fn resize(&mut self, width: u32, height: u32) {
        if self.is_lost() {
            return;
        }
        let max = self.max_size();
        let (width, height) = (width.clamp(1, max), height.clamp(1, max));
        if (width, height) != (self.config.width, self.config.height) {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Draws `view` into the canvas. A frame the browser cannot give (the canvas was lost or
    /// hidden) is skipped; the next call tries again.
    pub fn render(&mut self, view: &View) {
        if self.is_lost() {
            return;
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                return;
            }
            _ => return,
        };
        let target = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let size = (self.config.width, self.config.height);
        self.points.draw(
            &self.device,
            &self.queue,
            &target,
            self.config.format,
            size,
            view,
        );
        self.queue.present(texture);
    }

    /// Renders `view` off screen at the canvas's size and starts reading the picture back
    /// (await [`PendingPicture::pixels`]). Gives the same pixels as the canvas shows, the
    /// canvas being non-sRGB.
    pub fn read_pixels(&mut self, view: &View) -> PendingPicture {
        readback::start_read_pixels(
            &self.device,
            &self.queue,
            &mut self.points,
            (self.config.width, self.config.height),
            view,
        )
    }

    /// Starts waiting for all work submitted so far (await [`PendingWork::wait`]).
    pub fn finish(&self) -> PendingWork {
        readback::start_finish(&self.device, &self.queue)
    }
}

/// The drawing buffer's first size: the canvas's own width and height attributes.
fn canvas_size(canvas: &HtmlCanvasElement) -> (u32, u32) {
    (canvas.width().max(1), canvas.height().max(1))
}

/// Opens WebGPU: adapter and device first, the canvas last.
async fn open_webgpu(canvas: &HtmlCanvasElement) -> std::result::Result<Gpu, String> {
    if !has_navigator_gpu() {
        return Err("navigator.gpu is missing (WebGPU is off or unsupported)".into());
    }
    let instance = wgpu::Instance::new(instance_descriptor(wgpu::Backends::BROWSER_WEBGPU));
    let adapter = instance
        .request_adapter(&adapter_options(None))
        .await
        .map_err(|e| format!("no adapter ({e})"))?;
    let (device, queue) = request_device(&adapter).await?;
    let surface = instance
        .create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone()))
        .map_err(|e| format!("cannot use the canvas ({e})"))?;
    finish_opening(
        Backend::WebGpu,
        instance,
        adapter,
        device,
        queue,
        surface,
        canvas,
    )
}

/// Opens WebGL2: the canvas first (wgpu's GL backend finds its adapter through the canvas).
async fn open_webgl2(canvas: &HtmlCanvasElement) -> std::result::Result<Gpu, String> {
    let instance = wgpu::Instance::new(instance_descriptor(wgpu::Backends::GL));
    let surface = instance
        .create_surface(wgpu::SurfaceTarget::Canvas(canvas.clone()))
        .map_err(|e| format!("cannot use the canvas ({e})"))?;
    let adapter = instance
        .request_adapter(&adapter_options(Some(&surface)))
        .await
        .map_err(|e| format!("no adapter ({e})"))?;
    let (device, queue) = request_device(&adapter).await?;
    finish_opening(
        Backend::WebGl2,
        instance,
        adapter,
        device,
        queue,
        surface,
        canvas,
    )
}

fn instance_descriptor(backends: wgpu::Backends) -> wgpu::InstanceDescriptor {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    desc
}

fn adapter_options<'a, 'b>(
    surface: Option<&'a wgpu::Surface<'b>>,
) -> wgpu::RequestAdapterOptions<'a, 'b> {
    wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: surface,
        apply_limit_buckets: false,
    }
}

/// A device with WebGL2-level limits (all the viewer needs), except the texture size and buffer
/// size, which follow the adapter so that large canvases and clouds work where the GPU allows.
async fn request_device(
    adapter: &wgpu::Adapter,
) -> std::result::Result<(wgpu::Device, wgpu::Queue), String> {
    let supported = adapter.limits();
    let mut limits = wgpu::Limits::downlevel_webgl2_defaults().using_resolution(supported.clone());
    limits.max_buffer_size = supported.max_buffer_size;
    let (device, queue) = adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("viewer"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        })
        .await
        .map_err(|e| format!("no device ({e})"))?;
    // Report GPU validation errors on the console instead of aborting the module.
    device.on_uncaptured_error(Arc::new(|error| {
        web_sys::console::error_1(&format!("3D view GPU error: {error}").into());
    }));
    Ok((device, queue))
}

fn finish_opening(
    backend: Backend,
    instance: wgpu::Instance,
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    surface: wgpu::Surface<'static>,
    canvas: &HtmlCanvasElement,
) -> std::result::Result<Gpu, String> {
    let (width, height) = canvas_size(canvas);
    let max = device.limits().max_texture_dimension_2d;
    let mut config = surface
        .get_default_config(&adapter, width.min(max), height.min(max))
        .ok_or("the canvas cannot be drawn by this adapter")?;
    let capabilities = surface.get_capabilities(&adapter);
    if let Some(&plain) = capabilities.formats.iter().find(|f| !f.is_srgb()) {
        config.format = plain;
    }
    if capabilities
        .alpha_modes
        .contains(&wgpu::CompositeAlphaMode::Opaque)
    {
        config.alpha_mode = wgpu::CompositeAlphaMode::Opaque;
    }
    surface.configure(&device, &config);
    let points = PointPass::new(&device);
    let lost = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&lost);
    device.set_device_lost_callback(move |_reason, _message| {
        flag.store(true, Ordering::Relaxed);
        // Tell the page (the callback may not hold the canvas): it opens a new viewer.
        if let Some(window) = web_sys::window()
            && let Ok(event) = web_sys::Event::new(LOST_EVENT)
        {
            let _ = window.dispatch_event(&event);
        }
    });
    Ok(Gpu {
        backend,
        adapter_name: adapter.get_info().name,
        device,
        queue,
        surface,
        config,
        points,
        lost,
        _instance: instance,
    })
}

/// Whether `navigator.gpu` exists (checked before asking wgpu, which would otherwise fall back
/// on its own).
fn has_navigator_gpu() -> bool {
    let Some(window) = web_sys::window() else {
        return false;
    };
    js_sys::Reflect::get(&window.navigator(), &"gpu".into())
        .is_ok_and(|gpu| !gpu.is_undefined() && !gpu.is_null())
}

/// Waits about `ms` milliseconds without blocking the browser (a `setTimeout` promise).
pub(crate) async fn sleep(ms: i32) {
    let promise = js_sys::Promise::new(&mut |resolve, _reject| {
        let scheduled = web_sys::window().map(|w| {
            w.set_timeout_with_callback_and_timeout_and_arguments_0(resolve.unchecked_ref(), ms)
        });
        if !matches!(scheduled, Some(Ok(_))) {
            // No window (a worker): resolve at once; callers poll again anyway.
            let _ = resolve.call0(&wasm_bindgen::JsValue::NULL);
        }
    });
    let _ = JsFuture::from(promise).await;
}
