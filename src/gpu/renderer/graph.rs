//! The frame's passes as one declared list ([`GRAPH`]): each pass's name (its timing label),
//! when it runs, what it reads and writes, and how it encodes. The renderer records them in
//! this order, skipping those that do not run; the timings are labelled by these names; the
//! buffer read back as the indirect light is the output of the last running pass that writes
//! `indirect`; and the pass table of `docs/design.md` is [`pass_table`] (a test holds the
//! two together). Adding a pass touches its shader, its Rust file and this list.

use super::{Drawn, GpuFrame, Renderer};
use anyhow::Result;

/// One pass of the frame.
pub struct FramePass {
    /// Its timing label in run records.
    pub name: &'static str,
    /// Its Rust and WGSL files.
    pub files: &'static str,
    /// When it runs (for the docs); [`FramePass::runs`] decides.
    pub when: &'static str,
    /// The named resources it reads and writes.
    pub reads: &'static [&'static str],
    pub writes: &'static [&'static str],
    /// What it computes (for the docs).
    pub what: &'static str,
    runs: fn(&Renderer) -> bool,
    encode: fn(&mut Renderer, &mut wgpu::CommandEncoder, &mut Frame) -> Result<()>,
}

impl FramePass {
    /// Whether the pass runs in `r` (from the renderer's settings and the scene).
    pub fn runs(&self, r: &Renderer) -> bool {
        (self.runs)(r)
    }
    pub(crate) fn encode(
        &self,
        r: &mut Renderer,
        enc: &mut wgpu::CommandEncoder,
        f: &mut Frame,
    ) -> Result<()> {
        (self.encode)(r, enc, f)
    }
}

/// What the passes of one frame share: the frame, the slots whose ISM tiles are redrawn, the
/// depth ranges, and what the raster passes report.
pub(crate) struct Frame<'a, 'b> {
    pub input: &'a GpuFrame<'b>,
    pub changed_slots: u32,
    pub geometry_kept: bool,
    /// The ISMs' and hemicubes' depth range, and the G-buffer's camera.
    pub near: f32,
    pub far: f32,
    pub view_proj: glam::Mat4,
    /// What the raster passes drew, and whether the shadow maps were drawn this frame.
    pub drawn: Drawn,
    pub shadows_drawn: bool,
}

fn always(_: &Renderer) -> bool {
    true
}

/// The passes of a frame, in order.
pub const GRAPH: [FramePass; 11] = [
    FramePass {
        name: "gbuffer",
        files: "`gpu/gbuffer.rs`, `shaders/gbuffer.wgsl`",
        when: "always",
        reads: &["vertices", "camera"],
        writes: &["gbuffer"],
        what: "per sub-sample the world position's float bits and triangle index + 1 (0: nothing), in an `Rgba32Uint` target; with `--aa S > 1`, S x S tiles of the image, tile (i, j) drawn with the projection moved to its sub-sample offset; what a view cannot see is left out (`scene::culling`)",
        runs: always,
        encode: |r, enc, f| {
            r.encode_gbuffer(enc, f);
            Ok(())
        },
    },
    FramePass {
        name: "surface",
        files: "`gpu/surface.rs`, `shaders/surface.wgsl`",
        when: "scenes with textures or vertex colours",
        reads: &["gbuffer", "tris", "textures"],
        writes: &["surface"],
        what: "each sample's textured albedo and emission (the other scenes use the triangle's)",
        runs: |r| r.surface.is_some(),
        encode: |r, enc, _| {
            let (gw, gh) = r.config.grid();
            if let Some(s) = &r.surface {
                s.encode(enc, gw, gh);
            }
            Ok(())
        },
    },
    FramePass {
        name: "shadow_maps",
        files: "`gpu/shadow.rs`, `shaders/shadow.wgsl`",
        when: "always (kept while the geometry and emitter samples are the same)",
        reads: &["vertices", "lights"],
        writes: &["hemicubes"],
        what: "per emitter sample up to 5 faces of an `R32Uint` array texture holding the distance's float bits: only the faces whose frustum meets the box of the geometry in front of the sample, or one window face over that box",
        runs: always,
        encode: |r, enc, f| {
            r.encode_shadows(enc, f);
            Ok(())
        },
    },
    FramePass {
        name: "direct",
        files: "`gpu/direct.rs`, `shaders/direct.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "lights", "hemicubes"],
        writes: &["direct"],
        what: "direct light per sub-sample from the emitter samples, with hemicube visibility",
        runs: always,
        encode: |r, enc, _| {
            let (gw, gh) = r.config.grid();
            r.direct.encode(enc, gw, gh);
            Ok(())
        },
    },
    FramePass {
        name: "ism_splat",
        files: "`gpu/ism.rs`, `shaders/ism_splat.wgsl`",
        when: "always (only the slots whose VPL or geometry changed)",
        reads: &["tris", "points", "vpls", "slots"],
        writes: &["ism atlas"],
        what: "each redrawn slot's paraboloid tile: the nearest depth per texel of its subset of the point set (`atomicMax` on an inverted depth), and its near-field cells from its ray-cast points",
        runs: always,
        encode: |r, enc, f| {
            let points = r.config.ism_points + r.near_points(f.input);
            r.ism.encode_splat(enc, f.changed_slots, points);
            Ok(())
        },
    },
    FramePass {
        name: "ism_pullpush",
        files: "`gpu/ism.rs`, `shaders/ism_pullpush.wgsl`",
        when: "always (only the redrawn slots)",
        reads: &["ism atlas"],
        writes: &["ism pyramid"],
        what: "holes filled within each tile up to 2^levels texels (levels 0 and 1 of the pyramid); tiles of at most 64 texels in one fused dispatch that also empties the atlas",
        runs: always,
        encode: |r, enc, f| {
            r.ism.encode_pull_push(enc, f.changed_slots);
            Ok(())
        },
    },
    FramePass {
        name: "gather",
        files: "`gpu/gather.rs`, `shaders/gather.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "vpls", "ism pyramid"],
        writes: &["indirect"],
        what: "the indirect light per pixel: the sum over the VPLs (with `--interleave n > 1`, over the pixel's subset of them, times n^2) with ISM visibility; supersampled, once per pixel without the albedo",
        runs: always,
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            r.gather.encode(enc, (iw, ih), r.config.interleave);
            Ok(())
        },
    },
    FramePass {
        name: "interleave",
        files: "`gpu/interleave.rs`, `shaders/interleave.wgsl`",
        when: "`--interleave n > 1`",
        reads: &["gbuffer", "surface", "tris", "indirect"],
        writes: &["indirect"],
        what: "the depth- and normal-aware mean of the subsets over the pixel's block (docs/math.md)",
        runs: |r| r.interleave.is_some(),
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            if let Some(p) = &r.interleave {
                p.encode(enc, iw, ih);
            }
            Ok(())
        },
    },
    FramePass {
        name: "temporal",
        files: "`gpu/temporal.rs`, `shaders/temporal.wgsl`",
        when: "`--accumulate N > 1`",
        reads: &["gbuffer", "tris", "indirect", "history"],
        writes: &["indirect", "history"],
        what: "the indirect light as the running mean of up to N frames' estimates of the pixel's surface point, while the triangles and emitter samples stay the same",
        runs: |r| r.temporal.is_some(),
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            if let Some(t) = &mut r.temporal {
                t.encode(enc, iw, ih);
            }
            Ok(())
        },
    },
    FramePass {
        name: "compose",
        files: "`gpu/compose.rs`, `shaders/compose.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "direct", "indirect"],
        writes: &["hdr", "ldr"],
        what: "emission + direct + indirect (linear), and the 8-bit preview; supersampled, each sub-sample's indirect light from its pixel's, times its albedo, and no preview",
        runs: always,
        encode: |r, enc, _| {
            let (gw, gh) = r.config.grid();
            r.compose.encode(enc, gw, gh);
            Ok(())
        },
    },
    FramePass {
        name: "downsample",
        files: "`gpu/downsample.rs`, `shaders/downsample.wgsl`",
        when: "`--aa S > 1`",
        reads: &["hdr", "direct", "indirect"],
        writes: &["hdr", "ldr", "direct", "indirect"],
        what: "the box filter of each pixel's S^2 sub-samples",
        runs: |r| r.downsample.is_some(),
        encode: |r, enc, _| {
            let c = &r.config;
            if let Some(p) = &r.downsample {
                p.encode(enc, c.width, c.height);
            }
            Ok(())
        },
    },
];

/// The pass table of `docs/design.md`, from [`GRAPH`].
pub fn pass_table() -> String {
    let mut t = String::from(
        "| pass (timing name) | Rust / WGSL | runs | reads | writes | what |\n| --- | --- | --- | --- | --- | --- |\n",
    );
    let list = |v: &[&str]| {
        v.iter()
            .map(|s| format!("`{s}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for p in &GRAPH {
        t += &format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            p.name,
            p.files,
            p.when,
            list(p.reads),
            list(p.writes),
            p.what
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The docs' table is the graph's, between the markers; `IRAD_BLESS=1` rewrites it.
    #[test]
    fn the_docs_pass_table_is_the_graph() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/design.md");
        let doc = std::fs::read_to_string(&path).unwrap();
        let (begin, end) = ("<!-- passes: begin -->\n", "<!-- passes: end -->");
        let a = doc
            .find(begin)
            .expect("docs/design.md has no pass table markers")
            + begin.len();
        let b = doc[a..].find(end).expect("no end marker") + a;
        let want = pass_table();
        if std::env::var_os("IRAD_BLESS").is_some() {
            std::fs::write(&path, format!("{}{want}{}", &doc[..a], &doc[b..])).unwrap();
            return;
        }
        assert_eq!(
            doc[a..b],
            want,
            "docs/design.md's pass table differs from gpu::graph::GRAPH: IRAD_BLESS=1 cargo test --release --lib pass_table rewrites it"
        );
    }

    /// Every pass reads only what an earlier pass (or the upload) wrote, and the names are
    /// unique: the order is a valid schedule.
    #[test]
    fn every_read_is_written_before() {
        let uploaded = [
            "vertices", "camera", "tris", "textures", "lights", "points", "vpls", "slots",
            "history",
        ];
        let mut written: Vec<&str> = uploaded.to_vec();
        let mut names = Vec::new();
        for p in &GRAPH {
            for r in p.reads {
                assert!(
                    written.contains(r),
                    "{} reads {r} before anything writes it",
                    p.name
                );
            }
            written.extend(p.writes);
            assert!(!names.contains(&p.name), "two passes named {}", p.name);
            names.push(p.name);
        }
        assert!(GRAPH.iter().any(|p| p.writes.contains(&"indirect")));
    }
}
