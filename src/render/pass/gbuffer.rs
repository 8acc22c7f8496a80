//! G-buffer pass: rasterises every object into normal + distance, albedo + material id, and
//! the subsurface-blurred normal, with depth testing.

use wgpu::util::DeviceExt;

use crate::render::graph::{read, sampler, texture_array, uniform, GraphError, PassDecl, Recorder};
use crate::render::textures::SAMPLERS;
use crate::scene::Scene;

pub const NORMAL_DISTANCE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const ALBEDO: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Stored as n·0.5 + 0.5 (signed normalised formats are not renderable in WebGPU).
pub const BLURRED_NORMAL: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Radiosity's irradiance per pixel.
pub const IRRADIANCE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Radiosity's per-vertex irradiance, a second vertex buffer: it changes as the solve refines
/// while the geometry stays put.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GiVertex {
    pub direct: [f32; 4],
    pub indirect: [f32; 4],
}

pub const GI_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<GiVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![4 => Float32x4, 5 => Float32x4],
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    blurred_normal: [f32; 3],
    material: u32,
    /// Linear RGBA base-colour tint, 8 bits per channel.
    tint: [u8; 4],
    /// Texture coordinates: xy base colour map, zw normal and occlusion maps.
    uv: [f32; 4],
    /// Tangent and bitangent sign (normal maps).
    tangent: [f32; 4],
}

/// The vertex layout the G-buffer and photon passes share.
pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Uint32, 6 => Unorm8x4, 7 => Float32x4, 8 => Float32x4],
};

/// A scene's mesh on the GPU.
pub struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
    /// `GiVertex` per vertex; zeros until (and unless) radiosity writes it.
    pub gi: wgpu::Buffer,
    /// Which maps the scene has: the G-buffer's pipeline reads only those.
    pub maps: MapUse,
}

/// The kinds of map a scene's materials use, and whether any clamps or mirrors: the
/// G-buffer's pipeline is specialised for them (the shader's override constants), as a
/// software adapter pays for a map read on every pixel whether or not its material has one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MapUse {
    pub base: bool,
    pub normal: bool,
    pub occlusion: bool,
    pub wrap_modes: bool,
}

impl MapUse {
    pub fn of(scene: &Scene) -> MapUse {
        fn any<T>(per_material: &[Option<T>]) -> bool {
            per_material.iter().any(Option::is_some)
        }
        MapUse {
            base: any(&scene.material_textures),
            normal: any(&scene.material_normal_maps),
            occlusion: any(&scene.material_occlusion_maps),
            wrap_modes: scene
                .textures
                .iter()
                .chain(&scene.linear_maps)
                .any(|t| t.sampling.code() != 0),
        }
    }

    /// The pipeline cache's key for this set: one bit each.
    fn variant(self) -> u32 {
        [self.base, self.normal, self.occlusion, self.wrap_modes]
            .iter()
            .enumerate()
            .map(|(i, &on)| u32::from(on) << i)
            .sum()
    }

    /// The shader's override constants for this set.
    fn constants(self) -> [(&'static str, f64); 4] {
        let f = |on: bool| f64::from(u8::from(on));
        [
            ("BASE_MAPS", f(self.base)),
            ("NORMAL_MAPS", f(self.normal)),
            ("OCCLUSION_MAPS", f(self.occlusion)),
            ("WRAP_MODES", f(self.wrap_modes)),
        ]
    }
}

pub const PASS: PassDecl = PassDecl {
    label: "gbuffer",
    shader: include_str!("../../../shaders/gbuffer.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("materials.scene"),
        texture_array("materials.textures"),
        sampler("materials.sampler"),
        texture_array("materials.linear_maps"),
        sampler(SAMPLERS[1]),
        sampler(SAMPLERS[2]),
        sampler(SAMPLERS[3]),
        sampler(SAMPLERS[4]),
        sampler(SAMPLERS[5]),
        sampler(SAMPLERS[6]),
        sampler(SAMPLERS[7]),
        sampler(SAMPLERS[8]),
    ],
    attachments: &[
        "gbuffer.normal_distance",
        "gbuffer.albedo",
        "gbuffer.blurred_normal",
        "gbuffer.irradiance",
        "gbuffer.depth",
    ],
    entry_points: &["vs_main", "fs_main"],
};

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    maps: MapUse,
) -> wgpu::RenderPipeline {
    let targets = [NORMAL_DISTANCE, ALBEDO, BLURRED_NORMAL, IRRADIANCE];
    // No culling here: the fragment shader culls per material (double-sided ones keep their
    // back faces).
    let constants = maps.constants();
    mesh_pipeline(
        device, PASS.label, layout, module, &targets, None, &constants,
    )
}

/// A pipeline that rasterises the scene mesh (`vs_main`/`fs_main`, the mesh and radiosity
/// vertex buffers, nearest depth wins) into `targets`: the G-buffer's and the photon pass's.
pub fn mesh_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    targets: &[wgpu::TextureFormat],
    cull_mode: Option<wgpu::Face>,
    fragment_constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let targets: Vec<_> = targets
        .iter()
        .map(|f| Some(wgpu::ColorTargetState::from(*f)))
        .collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(VERTEX_LAYOUT), Some(GI_LAYOUT)],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: fragment_constants,
                ..Default::default()
            },
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Rasterises `mesh` into the G-buffer targets.
pub fn record(f: &mut Recorder, mesh: &MeshBuffers) -> Result<(), GraphError> {
    let maps = mesh.maps;
    let pipeline = f
        .pipelines
        .render(&PASS, maps.variant(), |d, l, m| pipeline(d, l, m, maps));
    let bind_group = f.bind_group(&PASS)?;
    let view = |name| f.view(name).cloned();
    let (nd, albedo, blurred, irradiance, depth) = (
        view("gbuffer.normal_distance")?,
        view("gbuffer.albedo")?,
        view("gbuffer.blurred_normal")?,
        view("gbuffer.irradiance")?,
        view("gbuffer.depth")?,
    );
    let clear = |view, color: wgpu::Color| {
        Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(color),
                store: wgpu::StoreOp::Store,
            },
        })
    };
    // Distance −1 marks "no surface": it can never pass the reprojection test.
    let no_surface = wgpu::Color {
        r: 0.0,
        g: 0.0,
        b: 0.0,
        a: -1.0,
    };
    let mut pass = f.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(PASS.label),
        color_attachments: &[
            clear(&nd, no_surface),
            clear(&albedo, wgpu::Color::TRANSPARENT),
            clear(&blurred, wgpu::Color::TRANSPARENT),
            clear(&irradiance, wgpu::Color::TRANSPARENT),
        ],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: f.timer.render(PASS.label),
        occlusion_query_set: None,
        multiview_mask: None,
    });
    draw_mesh(&mut pass, &pipeline, &bind_group, mesh);
    Ok(())
}

/// Draws the whole scene mesh (with its radiosity vertex buffer) in a raster pass: what the
/// G-buffer, photon and shadow passes each do once.
pub fn draw_mesh(
    pass: &mut wgpu::RenderPass,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
    mesh: &MeshBuffers,
) {
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.set_vertex_buffer(0, mesh.vertices.slice(..));
    pass.set_vertex_buffer(1, mesh.gi.slice(..));
    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..mesh.index_count, 0, 0..1);
}

/// Uploads a scene's mesh (vertex, index and radiosity buffers).
pub fn upload(device: &wgpu::Device, scene: &Scene) -> MeshBuffers {
    let mesh = &scene.mesh;
    let vertices: Vec<Vertex> = (0..mesh.positions.len())
        .map(|i| Vertex {
            position: mesh.positions[i].to_array(),
            normal: mesh.normals[i].to_array(),
            blurred_normal: mesh.blurred_normals[i].to_array(),
            material: mesh.material[i],
            tint: mesh.tint[i].map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8),
            uv: mesh.uv[i],
            tangent: mesh.tangent[i],
        })
        .collect();
    let label = Some(scene.name());
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label,
        contents: bytemuck::cast_slice(&vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label,
        contents: bytemuck::cast_slice(&mesh.indices),
        usage: wgpu::BufferUsages::INDEX,
    });
    let gi = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("gi"),
        contents: bytemuck::cast_slice(&vec![
            <GiVertex as bytemuck::Zeroable>::zeroed();
            mesh.positions.len().max(1)
        ]),
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
    });
    MeshBuffers {
        vertices,
        indices,
        index_count: mesh.indices.len() as u32,
        gi,
        maps: MapUse::of(scene),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pipeline_reads_only_the_maps_a_scene_has() {
        let of = |name| MapUse::of(&Scene::builtin(name).expect("builtin scene"));
        // JSON scenes have no maps: all three reads are compiled out.
        assert_eq!(of("opaque"), MapUse::default());
        // The glTF gallery's tiles have a base colour and a normal map, no occlusion map,
        // and every map repeats.
        let gallery = of("gallery");
        assert!(gallery.base && gallery.normal);
        assert!(!gallery.occlusion && !gallery.wrap_modes);
        // Every set is its own pipeline, and its constants say what it holds.
        let sets: Vec<MapUse> = (0..16u32)
            .map(|k| MapUse {
                base: k & 1 != 0,
                normal: k & 2 != 0,
                occlusion: k & 4 != 0,
                wrap_modes: k & 8 != 0,
            })
            .collect();
        for (k, set) in sets.iter().enumerate() {
            assert_eq!(set.variant(), k as u32);
            let on: Vec<bool> = set.constants().iter().map(|(_, v)| *v == 1.0).collect();
            assert_eq!(on, [set.base, set.normal, set.occlusion, set.wrap_modes]);
        }
    }
}
