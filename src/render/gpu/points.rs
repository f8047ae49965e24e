//! The point pass: GPU buffers of the drawn points, the render pipelines of `points.wgsl` (one
//! per target format), a depth buffer, and the draw itself.

use crate::render::view::{Uniforms, View};

/// Bytes per point in the position buffer: X and X', 3 × f32 each.
const POSITION_STRIDE: u64 = 24;
/// Bytes per point in the colour buffer: frame-1 and frame-2 RGBA bytes.
const COLOUR_STRIDE: u64 = 8;
/// Depth buffer format (WebGPU and WebGL2 both render to it).
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Most points whose position buffer fits `device`'s buffer size limit.
pub(super) fn max_points(device: &wgpu::Device) -> usize {
    (device.limits().max_buffer_size / POSITION_STRIDE).min(u32::MAX as u64) as usize
}

/// A GPU buffer that holds one packed array and its version in the [`View`].
struct Uploaded {
    buffer: wgpu::Buffer,
    version: u64,
}

struct DepthBuffer {
    view: wgpu::TextureView,
    size: (u32, u32),
}

pub(super) struct PointPass {
    shader: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    /// Pipelines made so far, one per colour target format.
    pipelines: Vec<(wgpu::TextureFormat, wgpu::RenderPipeline)>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    positions: Option<Uploaded>,
    colours: Option<Uploaded>,
    count: u32,
    depth: Option<DepthBuffer>,
}

impl PointPass {
    pub(super) fn new(device: &wgpu::Device) -> PointPass {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("points.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("points.wgsl").into()),
        });
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("point uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(Uniforms::SIZE as u64),
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("points"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("point uniforms"),
            size: Uniforms::SIZE as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("point uniforms"),
            layout: &bind_group_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        PointPass {
            shader,
            layout,
            pipelines: Vec::new(),
            uniforms,
            bind_group,
            positions: None,
            colours: None,
            count: 0,
            depth: None,
        }
    }

    /// Draws `view` into `target` (of `format`, `size` pixels): clears to the background, then
    /// draws every shown point as a quad, depth-tested. Submits the work.
    pub(super) fn draw(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        size: (u32, u32),
        view: &View,
    ) {
        self.upload(device, queue, view);
        queue.write_buffer(&self.uniforms, 0, &view.uniforms().to_bytes());
        let depth = self.depth_view(device, size);
        let pipeline = self.pipeline(device, format);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("points"),
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("points"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_colour(view.background(), format)),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(positions), Some(colours)) = (&self.positions, &self.colours)
                && self.count > 0
            {
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_vertex_buffer(0, positions.buffer.slice(..));
                pass.set_vertex_buffer(1, colours.buffer.slice(..));
                pass.draw(0..4, 0..self.count);
            }
        }
        queue.submit([encoder.finish()]);
    }

    /// Copies the view's packed positions and colours to the GPU when their versions changed,
    /// growing the buffers as needed.
    fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, view: &View) {
        let (positions, positions_version) = view.positions();
        let (colours, colours_version) = view.colours();
        let count = colours.len() / 2;
        sync_buffer(
            device,
            queue,
            &mut self.positions,
            bytemuck::cast_slice(positions),
            positions_version,
            "point positions",
        );
        sync_buffer(
            device,
            queue,
            &mut self.colours,
            bytemuck::cast_slice(colours),
            colours_version,
            "point colours",
        );
        self.count = u32::try_from(count.min(positions.len() / 6)).unwrap_or(u32::MAX);
    }

    /// The depth buffer for `size`, made anew when the size changed.
    fn depth_view(&mut self, device: &wgpu::Device, size: (u32, u32)) -> wgpu::TextureView {
        if let Some(depth) = &self.depth
            && depth.size == size
        {
            return depth.view.clone();
        }
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("point depth"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.depth = Some(DepthBuffer {
            view: view.clone(),
            size,
        });
        view
    }

    /// The pipeline for colour targets of `format`, made on first use.
    fn pipeline(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        if let Some((_, pipeline)) = self.pipelines.iter().find(|(f, _)| *f == format) {
            return pipeline.clone();
        }
        let position_attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let colour_attributes = wgpu::vertex_attr_array![2 => Unorm8x4, 3 => Unorm8x4];
        let buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: POSITION_STRIDE,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &position_attributes,
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: COLOUR_STRIDE,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &colour_attributes,
            }),
        ];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("points"),
            layout: Some(&self.layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &buffers,
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &self.shader,
                entry_point: Some(if format.is_srgb() {
                    "fs_srgb"
                } else {
                    "fs_plain"
                }),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        self.pipelines.push((format, pipeline.clone()));
        pipeline
    }
}

/// Writes `bytes` to `slot` unless it already holds `version`; makes a larger buffer when the
/// data outgrew it. Buffers are never empty (wgpu rejects zero-sized vertex buffers).
fn sync_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slot: &mut Option<Uploaded>,
    bytes: &[u8],
    version: u64,
    label: &str,
) {
    if slot.as_ref().is_some_and(|s| s.version == version) {
        return;
    }
    let needed = (bytes.len() as u64).max(wgpu::COPY_BUFFER_ALIGNMENT);
    if slot.as_ref().is_none_or(|s| s.buffer.size() < needed) {
        *slot = Some(Uploaded {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: needed.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            version,
        });
    }
    if let Some(slot) = slot {
        if !bytes.is_empty() {
            queue.write_buffer(&slot.buffer, 0, bytes);
        }
        slot.version = version;
    }
}

/// The clear colour for background sRGB bytes on a target of `format`: the bytes as they are
/// for a plain target, linearised for an sRGB target (which encodes them back).
fn clear_colour([r, g, b]: [u8; 3], format: wgpu::TextureFormat) -> wgpu::Color {
    let channel = |byte: u8| {
        let c = byte as f64 / 255.0;
        if !format.is_srgb() {
            c
        } else if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    wgpu::Color {
        r: channel(r),
        g: channel(g),
        b: channel(b),
        a: 1.0,
    }
}
