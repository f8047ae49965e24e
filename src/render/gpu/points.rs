//! The point pass: the drawn points' data in two textures, the render pipelines of
//! `points.wgsl` (one per target format), a depth buffer, and the draw itself.
//!
//! How points are drawn, and why. Each point is one triangle around its square (the fragment
//! shader drops the rest), whose three vertices fetch the point's data from textures by vertex
//! index ("vertex pulling"), all in a single non-instanced draw call. Measured in headless
//! Chromium (SwiftShader, shared 2-core machine, 200 000 points): instancing a 4-vertex quad per
//! point took 6.7 s per frame (SwiftShader runs each instance as its own small draw, about 33 µs
//! per point, on WebGPU and WebGL2 alike); vertex pulling with two triangles per point 0.64 s;
//! one triangle per point halves the triangle setups again (500 000 points: 1.8 → 0.9 s on
//! WebGPU, 1.3 → 0.5 s on WebGL2). Small instances are a known weak spot of hardware GPUs too.
//! Textures rather than storage buffers, because WebGL2 has none.

use crate::render::view::{Uniforms, View};

/// Texels per row of the point textures: 2048, the largest size WebGL2 always allows. Each
/// point takes two texels of a row (frame 1, frame 2), so a row holds 1024 points.
const TEXTURE_WIDTH: u32 = 2048;
/// Positions: X or X' as (x, y, z, 1) float texels.
const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Colours: sRGB bytes as unorm texels, read back as the bytes / 255.
const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Vertices per point: one triangle around the square.
const VERTICES_PER_POINT: u32 = 3;
/// Texture rows uploaded at a time (32 768 points: 1 MiB of positions): the points are packed
/// and copied a slice at a time, so neither the view nor wgpu's staging (a CPU-side copy in wasm
/// memory on WebGL2) ever holds the whole packed cloud.
const UPLOAD_ROWS: usize = 32;
/// Depth buffer format (WebGPU and WebGL2 both render to it).
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Most points whose textures fit `device` (at least 2 097 152: 2048 rows of 1024 points).
pub(super) fn max_points(device: &wgpu::Device) -> usize {
    (TEXTURE_WIDTH / 2) as usize * device.limits().max_texture_dimension_2d as usize
}

/// The two point textures, `rows` rows tall, and the bind group that reads them.
struct PointTextures {
    positions: wgpu::Texture,
    colours: wgpu::Texture,
    rows: u32,
    bind_group: wgpu::BindGroup,
    /// Versions (from the [`View`]) of the data in the textures; `None` before the first upload.
    positions_version: Option<u64>,
    colours_version: Option<u64>,
}

struct DepthBuffer {
    view: wgpu::TextureView,
    size: (u32, u32),
}

pub(super) struct PointPass {
    shader: wgpu::ShaderModule,
    bind_group_layout: wgpu::BindGroupLayout,
    layout: wgpu::PipelineLayout,
    /// Pipelines made so far, one per colour target format.
    pipelines: Vec<(wgpu::TextureFormat, wgpu::RenderPipeline)>,
    uniforms: wgpu::Buffer,
    textures: PointTextures,
    count: u32,
    depth: Option<DepthBuffer>,
}

impl PointPass {
    pub(super) fn new(device: &wgpu::Device) -> PointPass {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("points.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("points.wgsl").into()),
        });
        let point_texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("points"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(Uniforms::SIZE as u64),
                    },
                    count: None,
                },
                point_texture(1),
                point_texture(2),
            ],
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
        let textures = PointTextures::new(device, &bind_group_layout, &uniforms, 1);
        PointPass {
            shader,
            bind_group_layout,
            layout,
            pipelines: Vec::new(),
            uniforms,
            textures,
            count: 0,
            depth: None,
        }
    }

    /// Draws `view` into `target` (of `format`, `size` pixels): clears to the background, then
    /// draws every shown point as a square (one triangle, fetched from the textures),
    /// depth-tested. Submits the work.
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
            if self.count > 0 {
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &self.textures.bind_group, &[]);
                pass.draw(0..self.count * VERTICES_PER_POINT, 0..1);
            }
        }
        queue.submit([encoder.finish()]);
    }

    /// Copies the view's packed positions and colours into the textures when their versions
    /// changed, a few rows at a time ([`UPLOAD_ROWS`]), making taller textures when the points
    /// outgrew them.
    fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, view: &View) {
        let texels = 2 * view.shown_len();
        let rows = texels.div_ceil(TEXTURE_WIDTH as usize).max(1) as u32;
        if rows > self.textures.rows {
            // Grow by powers of two so that a slowly growing cloud does not reallocate often.
            let rows = rows
                .next_power_of_two()
                .min(device.limits().max_texture_dimension_2d);
            self.textures =
                PointTextures::new(device, &self.bind_group_layout, &self.uniforms, rows);
        }
        // What fits the textures (a budget larger than the GPU allows is capped by the viewer).
        let points = view
            .shown_len()
            .min(self.textures.rows as usize * (TEXTURE_WIDTH / 2) as usize);
        let textures = &mut self.textures;
        if textures.positions_version != Some(view.positions_version()) {
            upload_points(
                queue,
                &textures.positions,
                16,
                points,
                |first, count, out| view.pack_positions(first, count, out),
            );
            textures.positions_version = Some(view.positions_version());
        }
        if textures.colours_version != Some(view.colours_version()) {
            upload_points(queue, &textures.colours, 4, points, |first, count, out| {
                view.pack_colours(first, count, out)
            });
            textures.colours_version = Some(view.colours_version());
        }
        self.count = u32::try_from(points).unwrap_or(u32::MAX);
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
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("points"),
            layout: Some(&self.layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
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

impl PointTextures {
    /// Textures `rows` rows tall (contents undefined until written) and their bind group.
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniforms: &wgpu::Buffer,
        rows: u32,
    ) -> PointTextures {
        let texture = |label, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: TEXTURE_WIDTH,
                    height: rows,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        };
        let positions = texture("point positions", POSITION_FORMAT);
        let colours = texture("point colours", COLOUR_FORMAT);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("points"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        &positions.create_view(&wgpu::TextureViewDescriptor::default()),
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(
                        &colours.create_view(&wgpu::TextureViewDescriptor::default()),
                    ),
                },
            ],
        });
        PointTextures {
            positions,
            colours,
            rows,
            bind_group,
            positions_version: None,
            colours_version: None,
        }
    }
}

/// Uploads the first `points` drawn points into `texture` (two texels of `texel_bytes` bytes
/// per point), `UPLOAD_ROWS` rows at a time: `pack(first, count, out)` appends the texels of
/// points `first..first + count` to `out`, so no packed copy of the whole cloud is ever held.
fn upload_points<T: bytemuck::Pod>(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    texel_bytes: usize,
    points: usize,
    pack: impl Fn(usize, usize, &mut Vec<T>),
) {
    let per_upload = UPLOAD_ROWS * (TEXTURE_WIDTH / 2) as usize;
    let mut packed = Vec::with_capacity(2 * per_upload.min(points));
    for first in (0..points).step_by(per_upload) {
        packed.clear();
        pack(first, per_upload.min(points - first), &mut packed);
        let row = 2 * first / TEXTURE_WIDTH as usize;
        write_texels(
            queue,
            texture,
            bytemuck::cast_slice(&packed),
            texel_bytes,
            row,
        );
    }
}

/// Writes `bytes` (texels of `texel_bytes` bytes each) into `texture` from the first texel of
/// row `first_row` on, row by row: the full rows in one copy, the rest of the last row in
/// another.
fn write_texels(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    bytes: &[u8],
    texel_bytes: usize,
    first_row: usize,
) {
    let row_bytes = TEXTURE_WIDTH as usize * texel_bytes;
    let full_rows = bytes.len() / row_bytes;
    let rest = bytes.len() % row_bytes;
    let copy = |data: &[u8], row: usize, width: usize, rows: usize| {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: (first_row + row) as u32,
                    z: 0,
                },
                aspect: wgpu::TextureAspect::All,
            },
            data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some((width * texel_bytes) as u32),
                rows_per_image: Some(rows as u32),
            },
            wgpu::Extent3d {
                width: width as u32,
                height: rows as u32,
                depth_or_array_layers: 1,
            },
        );
    };
    if full_rows > 0 {
        copy(
            &bytes[..full_rows * row_bytes],
            0,
            TEXTURE_WIDTH as usize,
            full_rows,
        );
    }
    if rest > 0 {
        copy(
            &bytes[full_rows * row_bytes..],
            full_rows,
            rest / texel_bytes,
            1,
        );
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
