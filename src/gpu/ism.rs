//! Imperfect shadow maps (`shaders/ism_splat.wgsl`, `shaders/ism_pullpush.wgsl`).
//!
//! The point set: points on the surfaces in proportion to area, kept as (triangle,
//! barycentrics) so they follow moving geometry, in random order. VPL slot s splats the
//! `ism_points` points starting at its own random offset, so each slot has its own random
//! subset, and a slot that keeps its VPL keeps its subset (and its tile, while the geometry is
//! still: only the slots the renderer lists are redrawn). Each splat writes the nearest depth
//! into the slot's paraboloid tile of one atlas (a storage buffer, atomicMax on an inverted
//! depth); pull-push then fills holes within each tile up to `2^levels` texels wide.

use super::bindings::{bytes, gpu_struct, params, read, read_write, Elem, Group, Pass};
use super::common::{FrameConstants, GpuVpl, Tri};
use super::{dispatch, groups_1d, Gpu};

pub use crate::vpl::ism_points::{
    near_directions, near_grid, near_points, point_set, pull_levels_run, seen_fraction,
    slot_offset, Point,
};

super::bindings::gpu_layout!(Point {
    tri: u32,
    b1: f32,
    b2: f32,
    pad: u32,
});

gpu_struct! {
    /// One pull-push level: its index, where it and its parent start in the pyramid, and
    /// its tile side.
    struct Level {
        level: u32,
        offset: u32,
        parent_offset: u32,
        size: u32,
    }
}

pub(crate) const SPLAT: Pass = Pass {
    name: "ism_splat",
    wgsl: include_str!("../../shaders/ism_splat.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            read("points", Elem::Struct(&Point::LAYOUT)),
            read("vpls", Elem::Struct(&GpuVpl::LAYOUT)),
            read("slots", Elem::Plain(8)),
            read_write("atlas", Elem::Plain(4)),
            read_write("near", Elem::Plain(16)),
        ],
    }],
};

pub(crate) const PULL_PUSH: Pass = Pass {
    name: "ism_pullpush",
    wgsl: include_str!("../../shaders/ism_pullpush.wgsl"),
    groups: &[
        Group {
            stages: wgpu::ShaderStages::COMPUTE,
            bindings: &[
                params("P", &FrameConstants::LAYOUT),
                read_write("atlas", Elem::Plain(4)),
                read_write("pyramid", Elem::Plain(4)),
                read("slots", Elem::Plain(8)),
                read_write("near", Elem::Plain(16)),
            ],
        },
        Group {
            stages: wgpu::ShaderStages::COMPUTE,
            bindings: &[params("L", &Level::LAYOUT)],
        },
    ],
};

pub struct Ism {
    clear: wgpu::ComputePipeline,
    splat: wgpu::ComputePipeline,
    splat_near: wgpu::ComputePipeline,
    decode: wgpu::ComputePipeline,
    pull: wgpu::ComputePipeline,
    push: wgpu::ComputePipeline,
    fused: wgpu::ComputePipeline,
    splat_group: wgpu::BindGroup,
    pp_group: wgpu::BindGroup,
    level_groups: Vec<wgpu::BindGroup>,
    /// What the splat writes: one tile of inverted depths (0: empty) a slot.
    pub atlas: wgpu::Buffer,
    /// The near-field cells the splat writes: [`near_grid`]^2 planes a slot (`vec4f`: the
    /// unit normal of the triangle its ray hit, in the VPL's frame, and its signed distance
    /// along it; zeros for none), see [`plane_depth`].
    pub near: wgpu::Buffer,
    /// Level 0 of the pyramid is the atlas the gather reads, its holes filled from level 1
    /// (see [`Ism::level1`]).
    pub pyramid: wgpu::Buffer,
    size: u32,
    levels: u32,
    /// Tiles in the atlas: one a VPL slot.
    tiles: u32,
    /// Tiles may hold an unfinished frame's splats: the next splat first clears them all.
    unclean: bool,
}

/// Bytes of the atlas for `slots` tiles of `size`^2.
pub fn atlas_bytes(slots: u32, size: u32) -> u64 {
    bytes::<u32>(slots as u64 * size as u64 * size as u64)
}

impl Ism {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        points: &wgpu::Buffer,
        vpls: &wgpu::Buffer,
        slots: &wgpu::Buffer,
        tiles: u32,
        size: u32,
        levels: u32,
    ) -> Self {
        // The renderer's grid (FrameConstants::near_grid), from the levels asked for.
        let cells = near_grid(size, levels) as u64;
        let levels = pull_levels_run(size, levels);
        let tile = |l: u32| tiles as u64 * ((size >> l) as u64).pow(2);
        let offsets_l: Vec<u64> = (0..=levels + 1)
            .scan(0u64, |acc, l| {
                let o = *acc;
                *acc += tile(l);
                Some(o)
            })
            .collect();
        let rw = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let atlas = gpu.buffer("ism atlas", atlas_bytes(tiles, size), rw);
        let near = gpu.buffer(
            "ism near-field cells",
            bytes::<[f32; 4]>(tiles as u64 * cells * cells),
            rw,
        );
        let pyramid = gpu.buffer(
            "ism pyramid",
            bytes::<f32>(offsets_l[levels as usize + 1]),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let m_splat = SPLAT.module(gpu);
        let l_splat = SPLAT.layouts(gpu);
        let splat = gpu.compute_pipeline(SPLAT.name, &m_splat, "main", &[&l_splat[0]]);
        let clear = gpu.compute_pipeline("ism clear", &m_splat, "clear", &[&l_splat[0]]);
        let splat_near =
            gpu.compute_pipeline("ism splat near", &m_splat, "near_main", &[&l_splat[0]]);
        let splat_group = SPLAT.groups[0].bind(
            gpu,
            SPLAT.name,
            &l_splat[0],
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("points", points.as_entire_binding()),
                ("vpls", vpls.as_entire_binding()),
                ("slots", slots.as_entire_binding()),
                ("atlas", atlas.as_entire_binding()),
                ("near", near.as_entire_binding()),
            ],
        );
        let m_pp = PULL_PUSH.module(gpu);
        let l = PULL_PUSH.layouts(gpu);
        let (l_pp, l_level) = (&l[0], &l[1]);
        let decode = gpu.compute_pipeline("ism decode", &m_pp, "decode", &[l_pp, l_level]);
        let pull = gpu.compute_pipeline("ism pull", &m_pp, "pull", &[l_pp, l_level]);
        let push = gpu.compute_pipeline("ism push", &m_pp, "push", &[l_pp, l_level]);
        // `fused` writes every value of its workgroup memory before reading it.
        let no_zeroing = wgpu::PipelineCompilationOptions {
            zero_initialize_workgroup_memory: false,
            ..Default::default()
        };
        let fused = gpu.compute_pipeline_with(
            "ism pull-push",
            &m_pp,
            "fused",
            &[l_pp, l_level],
            no_zeroing,
        );
        let pp_group = PULL_PUSH.groups[0].bind(
            gpu,
            PULL_PUSH.name,
            l_pp,
            &[
                ("P", params.as_entire_binding()),
                ("atlas", atlas.as_entire_binding()),
                ("pyramid", pyramid.as_entire_binding()),
                ("slots", slots.as_entire_binding()),
                ("near", near.as_entire_binding()),
            ],
        );
        let level_groups = (0..=levels)
            .map(|l| {
                let u = gpu.buffer(
                    "ism level",
                    std::mem::size_of::<Level>() as u64,
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                );
                let lv = Level {
                    level: l,
                    offset: offsets_l[l as usize] as u32,
                    parent_offset: offsets_l[l as usize + 1] as u32,
                    size: size >> l,
                };
                gpu.queue.write_buffer(&u, 0, bytemuck::bytes_of(&lv));
                PULL_PUSH.groups[1].bind(gpu, "ism level", l_level, &[("L", u.as_entire_binding())])
            })
            .collect();
        Ism {
            clear,
            splat,
            splat_near,
            decode,
            pull,
            push,
            fused,
            splat_group,
            pp_group,
            level_groups,
            atlas,
            near,
            pyramid,
            size,
            levels,
            tiles,
            unclean: false,
        }
    }

    /// Where level 1 starts in the pyramid (in values), 0 without pull-push levels.
    pub fn level1(&self) -> u32 {
        if self.levels == 0 {
            0
        } else {
            self.tiles * self.size * self.size
        }
    }

    /// After a frame that may have stopped between splat and pull-push: the next splat
    /// first clears every tile and near-field cell.
    pub fn forget(&mut self) {
        self.unclean = true;
    }

    /// Empties the tiles of the first `changed` entries of the slots buffer and splats their
    /// points; the other tiles are kept. The fused pull-push leaves the tiles it read empty,
    /// so tiles of at most [`FUSED_MAX`] texels need no clear but after [`Ism::forget`].
    /// The ray-cast near-field points (`near_points` a slot) go first: the point set's
    /// (`ism_points` a slot) reads their planes.
    pub fn encode_splat(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        changed: u32,
        (ism_points, near_points): (u32, u32),
    ) {
        debug_assert!(changed <= self.tiles);
        if changed == 0 {
            return;
        }
        if self.unclean {
            // A failed frame may have splatted any slot's tile and cells: all of them.
            enc.clear_buffer(&self.atlas, 0, None);
            enc.clear_buffer(&self.near, 0, None);
        } else if self.size > FUSED_MAX {
            let (x, y) = groups_1d(changed as u64 * (self.size as u64).pow(2));
            dispatch(
                enc,
                "ism clear",
                &self.clear,
                &[&self.splat_group],
                (x, y, 1),
            );
        }
        self.unclean = false;
        if near_points > 0 {
            dispatch(
                enc,
                "ism splat near",
                &self.splat_near,
                &[&self.splat_group],
                (near_points.div_ceil(64), changed, 1),
            );
        }
        dispatch(
            enc,
            "ism splat",
            &self.splat,
            &[&self.splat_group],
            (ism_points.div_ceil(64), changed, 1),
        );
    }

    /// Decodes the redrawn tiles of the atlas into the pyramid and fills their holes by
    /// pull-push: in one dispatch (a workgroup a tile, `fused`) for tiles of at most
    /// [`FUSED_MAX`] texels a side, else a dispatch per level over the pyramid.
    pub fn encode_pull_push(&self, enc: &mut wgpu::CommandEncoder, changed: u32) {
        // (The fused pass also empties the tiles it reads: see `encode_splat`.)
        if changed == 0 {
            return;
        }
        if self.size <= FUSED_MAX {
            let x = changed.min(65535);
            dispatch(
                enc,
                "ism pull-push",
                &self.fused,
                &[&self.pp_group, &self.level_groups[0]],
                (x, changed.div_ceil(x), 1),
            );
            return;
        }
        let texels = |l: u32| changed as u64 * ((self.size >> l) as u64).pow(2);
        let g = |n: u64| {
            let (x, y) = groups_1d(n);
            (x, y, 1)
        };
        dispatch(
            enc,
            "ism decode",
            &self.decode,
            &[&self.pp_group, &self.level_groups[0]],
            g(texels(0)),
        );
        for l in 0..self.levels {
            dispatch(
                enc,
                "ism pull",
                &self.pull,
                &[&self.pp_group, &self.level_groups[l as usize]],
                g(texels(l + 1)),
            );
        }
        // Down to level 1: the gather fills level 0's holes from it.
        for l in (1..self.levels).rev() {
            dispatch(
                enc,
                "ism push",
                &self.push,
                &[&self.pp_group, &self.level_groups[l as usize]],
                g(texels(l)),
            );
        }
    }
}

/// The largest tile side `shaders/ism_pullpush.wgsl`'s `fused` takes (its workgroup memory
/// holds the coarser levels of one tile).
pub const FUSED_MAX: u32 = 64;

/// The inverted depth (0: none) at which the direction of texel (`x`, `y`) of a tile of side
/// `size` (its centre mapped back from the paraboloid, in the VPL's frame) meets the plane of
/// a near-field cell, `q` = its unit normal in that frame and its signed distance along it
/// (`ism_splat.wgsl`, `near_plane`): none for an empty cell (zeros), a direction parallel to
/// the plane or one that leaves it behind. `far` is the depths' scale (`FrameConstants::far`).
///
/// Why a plane and not the depth along the cell's ray: a cell is several texels wide (13 cells
/// across the default 64-texel tile), and a VPL close to a surface (on a floor by a wall, in a
/// crevice's mouth just under a ceiling) has cells whose ray meets that surface while part of
/// the cell's directions pass beside it. One depth for the cell shut those directions too (a
/// crevice's fans 1-5 mm under a ceiling kept 0.68-0.69 of their light against exact
/// visibility, now 0.84-0.90; docs/math.md, "ISMs by a surface"); the plane shuts what lies
/// beyond the surface and nothing beside it.
pub fn plane_depth(q: [f32; 4], (x, y): (u32, u32), size: u32, far: f32) -> u32 {
    let fs = size as f32;
    let u = (x as f32 + 0.5) / fs * 2.0 - 1.0;
    let v = (y as f32 + 0.5) / fs * 2.0 - 1.0;
    let r2 = u * u + v * v;
    let w = glam::Vec3::new(2.0 * u, 2.0 * v, 1.0 - r2) / (1.0 + r2);
    let c = glam::Vec3::new(q[0], q[1], q[2]).dot(w);
    let t = q[3] / c;
    if !(c != 0.0 && t > 0.0) {
        return 0;
    }
    16777216 - ((t / far).min(1.0) * 16777215.0) as u32
}

/// CPU twin of the pull-push: level 0 of one tile of side `size` from its atlas texels
/// (inverted depths, 0: empty) and its `n` x `n` near-field cells (`near`, planes, see
/// [`plane_depth`]; n = 0: none), each texel the nearer of its own depth and where its
/// direction meets its cell's plane, holes filled from up to `levels` coarser levels; a value
/// is `depth + 4 * level`, -1 a hole left open.
pub fn pull_push(
    atlas: &[u32],
    (n, near): (u32, &[[f32; 4]]),
    (size, far): (u32, f32),
    levels: u32,
) -> Vec<f32> {
    let levels = pull_levels_run(size, levels);
    let decoded = |e: u32| {
        if e == 0 {
            -1.0
        } else {
            (16777216 - e) as f32 / 16777215.0
        }
    };
    let depth = |v: f32| v - 4.0 * (v * 0.25).floor();
    let cell = |i: u32| ((i / size) * n / size) * n + (i % size) * n / size;
    let level0 = (0..size * size).map(|i| {
        let e = atlas[i as usize];
        decoded(if n > 0 {
            e.max(plane_depth(
                near[cell(i) as usize],
                (i % size, i / size),
                size,
                far,
            ))
        } else {
            e
        })
    });
    let mut pyramid = vec![level0.collect::<Vec<f32>>()];
    for l in 0..levels {
        let (s, h) = ((size >> l) as usize, (size >> (l + 1)) as usize);
        let below = &pyramid[l as usize];
        let up = (0..h * h)
            .map(|k| {
                let at = (k / h) * 2 * s + (k % h) * 2;
                let (mut sum, mut count) = (0.0f32, 0.0f32);
                for v in [below[at], below[at + 1], below[at + s], below[at + s + 1]] {
                    if v >= 0.0 {
                        sum += depth(v);
                        count += 1.0;
                    }
                }
                if count > 0.0 {
                    sum / count + 4.0 * (l + 1) as f32
                } else {
                    -1.0
                }
            })
            .collect();
        pyramid.push(up);
    }
    for l in (0..levels as usize).rev() {
        let (s, h) = ((size >> l) as usize, (size >> (l + 1)) as usize);
        let (fine, coarse) = pyramid.split_at_mut(l + 1);
        for (i, v) in fine[l].iter_mut().enumerate() {
            if *v < 0.0 {
                *v = coarse[0][(i / s) / 2 * h + (i % s) / 2];
            }
        }
    }
    pyramid.swap_remove(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::BackendChoice;
    use rand::Rng;

    /// Both GPU paths (fused for 64, per level for 128) fill the same tiles as the CPU twin
    /// (level 0 with its holes read from level 1, as the gather does),
    /// on atlases from full to almost empty with near-field cells or without, for a subset
    /// of the slots (the others keep their tiles); the fused path leaves the atlas and
    /// near-field cells of the tiles it read empty, and the others' as they were.
    #[test]
    fn the_gpu_pull_push_matches_its_cpu_twin() {
        let gpu = match Gpu::new(BackendChoice::Auto) {
            Ok(g) => g,
            Err(e) => return println!("no GPU adapter, pull-push test skipped: {e}"),
        };
        let mut r = crate::math::rng(&[5, 0x9911]);
        for (size, levels, slots, cells) in [
            (64u32, 3u32, 6u32, true),
            (64, 3, 2, false),
            (16, 5, 3, true),
            (8, 0, 2, true),
            (128, 3, 3, true),
        ] {
            let per_tile = (size * size) as usize;
            // Each tile its own density of points: 0.5 to 90% of texels hit.
            let atlas: Vec<u32> = (0..slots as usize * per_tile)
                .map(|i| {
                    let density = [0.9, 0.2, 0.05, 0.005][(i / per_tile) % 4];
                    if r.random::<f64>() < density {
                        r.random_range(1..=16777216u32)
                    } else {
                        0
                    }
                })
                .collect();
            // A third of the cells hold a plane: a unit normal, at 1-60% of `far` either way.
            let n = if cells { near_grid(size, levels) } else { 0 };
            let far = 3.0f32;
            let near: Vec<[f32; 4]> = (0..(slots * n * n) as usize)
                .map(|_| {
                    if r.random::<f64>() < 0.3 {
                        let z: f32 = r.random_range(-1.0..1.0);
                        let phi = r.random_range(0.0..std::f32::consts::TAU);
                        let s = (1.0 - z * z).sqrt();
                        let m = glam::Vec3::new(s * phi.cos(), s * phi.sin(), z);
                        let c =
                            r.random_range(0.01..0.6) * far * if r.random() { 1.0 } else { -1.0 };
                        [m.x, m.y, m.z, c]
                    } else {
                        [0.0; 4]
                    }
                })
                .collect();
            let changed: Vec<[u32; 2]> = (0..slots).rev().step_by(2).map(|s| [s, 0]).collect();
            let params = FrameConstants {
                ism_size: size,
                pull_levels: levels,
                num_changed: changed.len() as u32,
                near_grid: n,
                far,
                ..bytemuck::Zeroable::zeroed()
            };
            let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
            let buffer = |label, data: &[u8]| {
                let b = gpu.buffer(label, data.len().max(16) as u64, storage);
                gpu.queue.write_buffer(&b, 0, data);
                b
            };
            let p = buffer("params", bytemuck::bytes_of(&params));
            let empty = buffer("unused", &[0u8; 1024]);
            let s = buffer("slots", bytemuck::cast_slice(&changed));
            let ism = Ism::new(&gpu, &p, &empty, &empty, &empty, &s, slots, size, levels);
            let params = FrameConstants {
                ism_level1: ism.level1(),
                ..params
            };
            gpu.queue.write_buffer(&p, 0, bytemuck::bytes_of(&params));
            gpu.queue
                .write_buffer(&ism.atlas, 0, bytemuck::cast_slice(&atlas));
            gpu.queue
                .write_buffer(&ism.near, 0, bytemuck::cast_slice(&near));
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            ism.encode_pull_push(&mut enc, changed.len() as u32);
            gpu.queue.submit([enc.finish()]);
            // Levels 0 and 1, as the gather reads them: level 0, at its holes level 1.
            let half = (size / 2) as usize;
            let level1 = ism.level1() as usize;
            let levels01 = per_tile + if level1 > 0 { half * half } else { 0 };
            let bytes = gpu
                .read_buffer(&ism.pyramid, 4 * slots as u64 * levels01 as u64)
                .unwrap();
            let pyramid: &[f32] = bytemuck::cast_slice(&bytes);
            let got: Vec<f32> = (0..slots as usize * per_tile)
                .map(|i| {
                    let v = pyramid[i];
                    if v >= 0.0 || level1 == 0 {
                        return v;
                    }
                    let (tile, k) = (i / per_tile, i % per_tile);
                    let (x, y) = (k % size as usize, k / size as usize);
                    pyramid[level1 + tile * half * half + (y / 2) * half + x / 2]
                })
                .collect();
            let read_u32 = |b: &wgpu::Buffer, len: usize| -> Vec<u32> {
                let bytes = gpu.read_buffer(b, (4 * len).max(4) as u64).unwrap();
                bytemuck::cast_slice(&bytes)[..len].to_vec()
            };
            let atlas_after = read_u32(&ism.atlas, atlas.len());
            let near_after: Vec<[f32; 4]> = {
                let bytes = gpu
                    .read_buffer(&ism.near, (16 * near.len()).max(4) as u64)
                    .unwrap();
                bytemuck::cast_slice(&bytes[..16 * near.len()]).to_vec()
            };
            let cells_of = (n as usize).pow(2);
            for tile in 0..slots as usize {
                let redone = changed.iter().any(|c| c[0] as usize == tile);
                let emptied = redone && size <= FUSED_MAX;
                let texels = tile * per_tile..(tile + 1) * per_tile;
                let cells = tile * cells_of..(tile + 1) * cells_of;
                for i in texels {
                    let want = if emptied { 0 } else { atlas[i] };
                    assert_eq!(atlas_after[i], want, "size {size}, tile {tile}, texel {i}");
                }
                for i in cells {
                    let want = if emptied { [0.0; 4] } else { near[i] };
                    assert_eq!(near_after[i], want, "size {size}, tile {tile}, cell {i}");
                }
            }
            for tile in 0..slots as usize {
                let range = tile * per_tile..(tile + 1) * per_tile;
                let redone = changed.iter().any(|c| c[0] as usize == tile);
                let cells = (n as usize).pow(2);
                let own = (n, &near[(tile * cells).min(near.len())..]);
                let want = if redone {
                    pull_push(&atlas[range.clone()], own, (size, far), levels)
                } else {
                    vec![0.0; per_tile] // never written: the buffer's zeros
                };
                for (i, (g, w)) in got[range].iter().zip(&want).enumerate() {
                    assert!(
                        (g - w).abs() <= 1e-6 * w.abs().max(1.0),
                        "size {size}, levels {levels}, tile {tile}, texel {i}: GPU {g}, CPU {w}"
                    );
                }
                if redone {
                    let holes = want.iter().filter(|&&v| v < 0.0).count();
                    println!("size {size}, levels {levels}, tile {tile}: {holes} holes left");
                }
            }
        }
    }
}
