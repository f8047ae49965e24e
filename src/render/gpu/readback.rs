//! Reading rendered frames back from the GPU (screenshots, tests) and waiting for the GPU.
//!
//! Browsers never block on the GPU, so each wait polls the device and yields to the event loop
//! (a short `setTimeout`) until wgpu reports the work done: on WebGPU the callbacks arrive from
//! the browser's event loop, on WebGL2 from `Device::poll`.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use crate::grid::Grid;
use crate::image::Frame;
use crate::render::view::View;
use crate::render::{RenderError, Result};

use super::points::PointPass;
use super::sleep;

/// Format of the off-screen picture: plain 8-bit RGBA, the canvas format on both backends.
const READBACK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Longest wait for the GPU before giving up, in milliseconds (software rendering of a large
/// cloud can take seconds).
const TIMEOUT_MS: f64 = 120_000.0;

const PENDING: u8 = 0;
const DONE: u8 = 1;
const FAILED: u8 = 2;

/// A picture being copied back from the GPU; [`PendingPicture::pixels`] waits for it. Holds
/// its own device handle, so nothing else need stay borrowed while it waits.
pub struct PendingPicture {
    device: wgpu::Device,
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    width: u32,
    height: u32,
    padded_row: usize,
}

/// Submitted GPU work; [`PendingWork::wait`] resolves when the GPU has done it.
pub struct PendingWork {
    device: wgpu::Device,
    state: Arc<AtomicU8>,
}

/// Renders `view` into an off-screen texture of `size` pixels and starts copying it back.
pub(super) fn start_read_pixels(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    points: &mut PointPass,
    (width, height): (u32, u32),
    view: &View,
) -> PendingPicture {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("screenshot"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: READBACK_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let target = texture.create_view(&wgpu::TextureViewDescriptor::default());
    points.draw(
        device,
        queue,
        &target,
        READBACK_FORMAT,
        (width, height),
        view,
    );

    // Rows in a copy must start at multiples of 256 bytes.
    let padded_row =
        (width as usize * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("screenshot read-back"),
        size: (padded_row * height as usize) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("screenshot copy"),
    });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row as u32),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);

    let state = Arc::new(AtomicU8::new(PENDING));
    let signal = Arc::clone(&state);
    buffer.map_async(wgpu::MapMode::Read, .., move |result| {
        signal.store(
            if result.is_ok() { DONE } else { FAILED },
            Ordering::Release,
        );
    });
    PendingPicture {
        device: device.clone(),
        buffer,
        state,
        width,
        height,
        padded_row,
    }
}

impl PendingPicture {
    /// The picture as RGB (alpha dropped; it is always opaque), rows top to bottom.
    pub async fn pixels(self) -> Result<Frame> {
        wait_for(&self.device, &self.state, "reading the picture back").await?;
        let row_bytes = self.width as usize * 4;
        let pixels = {
            let mapped = self
                .buffer
                .get_mapped_range(..)
                .map_err(|e| RenderError::Graphics(format!("cannot read the picture back: {e}")))?;
            let mut pixels = Vec::with_capacity(self.width as usize * self.height as usize);
            for row in mapped.chunks_exact(self.padded_row) {
                pixels.extend(row[..row_bytes].chunks_exact(4).map(|p| [p[0], p[1], p[2]]));
            }
            pixels
        };
        self.buffer.unmap();
        Grid::from_vec(self.width as usize, self.height as usize, pixels)
            .map_err(|e| RenderError::Graphics(format!("the picture read back is malformed: {e}")))
    }
}

/// Starts waiting for all work submitted to `queue` so far.
pub(super) fn start_finish(device: &wgpu::Device, queue: &wgpu::Queue) -> PendingWork {
    let state = Arc::new(AtomicU8::new(PENDING));
    let signal = Arc::clone(&state);
    queue.on_submitted_work_done(move || signal.store(DONE, Ordering::Release));
    PendingWork {
        device: device.clone(),
        state,
    }
}

impl PendingWork {
    /// Resolves once the GPU has done the work.
    pub async fn wait(self) -> Result<()> {
        wait_for(&self.device, &self.state, "waiting for the GPU").await
    }
}

/// Polls `device` and yields to the browser until `state` leaves PENDING.
async fn wait_for(device: &wgpu::Device, state: &AtomicU8, what: &str) -> Result<()> {
    let start = js_sys::Date::now();
    loop {
        // On WebGPU this does nothing; on WebGL2 it runs the callbacks of finished work.
        let _ = device.poll(wgpu::PollType::Poll);
        match state.load(Ordering::Acquire) {
            DONE => return Ok(()),
            FAILED => return Err(RenderError::Graphics(format!("{what} failed"))),
            _ => {}
        }
        if js_sys::Date::now() - start > TIMEOUT_MS {
            return Err(RenderError::Graphics(format!(
                "{what}: the GPU did not answer within {} s",
                TIMEOUT_MS / 1000.0
            )));
        }
        sleep(1).await;
    }
}
