//! A standalone repro of the memory growth seen on Vulkan through lavapipe (Mesa 22.3.6):
//! the `direct` pass's shader (shaders/common.wgsl + shaders/direct.wgsl) dispatched 600 times
//! on an empty G-buffer (every invocation returns early). With its parameters in a uniform
//! buffer (`uniform`) the process grows about 0.18 MiB a dispatch (78 -> 196 MiB): lavapipe
//! inlines uniform values that the light loop depends on and recompiles the shader at every
//! dispatch, keeping each copy. Without the loop (`noloop`), or with the parameters in a
//! read-only storage buffer as irad binds them (`storage`), it stays flat.
//! `cargo run --release --example lavapipe_growth -- [storage|uniform|noloop]`

fn rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(0.0, |pages| pages * 4096.0 / 1048576.0)
}

fn texture(
    device: &wgpu::Device,
    side: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    dim: wgpu::TextureViewDimension,
) -> wgpu::TextureView {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(dim),
        ..Default::default()
    })
}

fn main() -> anyhow::Result<()> {
    irad::gpu::quiet_mesa_runtime_dir();
    let mode = std::env::args().nth(1).unwrap_or_else(|| "storage".into());
    let gpu = irad::gpu::Gpu::new(irad::gpu::BackendChoice::Vulkan)?;
    println!("adapter: {}", gpu.adapter);
    let mut src = include_str!("../shaders/direct.wgsl").to_string();
    if mode != "storage" {
        src = src.replace(
            "var<storage, read> P: FrameConstants",
            "var<uniform> P: FrameConstants",
        );
    }
    if mode == "noloop" {
        let a = src.find("    for (var j = 0u;").expect("the light loop");
        let b = src.find("    direct[pix] = vec4f(sum").expect("the store");
        src = format!(
            "{}    sum = lights[0].radiance.xyz + vec3f(f32(textureLoad(shadows, vec2i(0), 0, 0).x));\n{}",
            &src[..a],
            &src[b..]
        );
    }
    let module = gpu.shader("direct probe", &src);
    let device = &gpu.device;
    let pipe = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = wgpu::BufferUsages::STORAGE;
    let params = gpu.buffer(
        "params",
        256,
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    );
    let mut p = [0u32; 24];
    (p[0], p[1], p[6], p[7]) = (256, 256, 1, 8);
    gpu.queue.write_buffer(&params, 0, bytemuck::cast_slice(&p));
    let (tris, lights, out) = (
        gpu.buffer("tris", 96 * 64, storage),
        gpu.buffer("lights", 48 * 4, storage),
        gpu.buffer("out", 256 * 256 * 16, storage),
    );
    let shadows = texture(
        device,
        8,
        5,
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureViewDimension::D2Array,
    );
    let gbuf = texture(
        device,
        256,
        1,
        wgpu::TextureFormat::Rgba32Uint,
        wgpu::TextureViewDimension::D2,
    );
    let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            entry(0, params.as_entire_binding()),
            entry(1, tris.as_entire_binding()),
            entry(2, lights.as_entire_binding()),
            entry(3, wgpu::BindingResource::TextureView(&shadows)),
            entry(4, wgpu::BindingResource::TextureView(&gbuf)),
            entry(5, out.as_entire_binding()),
        ],
    });
    for f in 0..=600 {
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut cp = enc.begin_compute_pass(&Default::default());
            cp.set_pipeline(&pipe);
            cp.set_bind_group(0, &group, &[]);
            cp.dispatch_workgroups(32, 32, 1);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        if f % 200 == 0 {
            println!("{mode} dispatch {f}: {:.1} MiB", rss_mib());
        }
    }
    Ok(())
}
