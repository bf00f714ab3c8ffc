//! The frame's passes as one declared list ([`GRAPH`], written with [`graph!`]): each pass's
//! name (its timing label), when it runs, what it reads and writes, how its GPU state is built
//! over the named resources of the passes before it ([`Builder`], which refuses a name the
//! entry does not declare), and how it encodes. [`Passes`] holds the built state, one field an
//! entry; the renderer records the passes in this order, skipping those that do not run; the
//! timings are labelled by these names; the buffers read back are the `hdr`, `ldr`, `direct`
//! and `indirect` the last passes that write them leave; and the pass table of
//! `docs/design.md` is [`pass_table`] (a test holds the two together). Adding a pass touches
//! its shader, its Rust file and this list.

use super::build::Builder;
use super::pass::FramePass;
use super::Renderer;
use crate::gpu::bindings::bytes;
use crate::gpu::common::Surface;
use crate::gpu::{
    check_size, compose::Compose, direct::Direct, downsample::Downsample, gather::Gather,
    gbuffer::GBuffer, interleave::Interleave, ism::Ism, shadow::ShadowMaps, surface::SurfacePass,
    temporal::HistorySample, temporal::Temporal,
};
use anyhow::Result;

/// Declares the graph: a list of `pass FramePass { .. },` entries, in order, each of which
/// may be preceded by `build FIELD: TYPE = |b| { .. };`, the [`Passes`] field holding the GPU
/// state its encode uses and how it is built from the [`Builder`] `b` (an entry without one
/// uses the state of the last entry before it that has one).
macro_rules! graph {
    ($( $(build $field:ident: $ty:ty = |$b:ident| $body:block;)? pass $pass:expr, )*) => {
        /// The passes of a frame, in order.
        pub const GRAPH: [FramePass; [$(stringify!($pass)),*].len()] = [$($pass,)*];
        static ENTRIES: [FramePass; GRAPH.len()] = GRAPH;
        /// Which entries of [`GRAPH`] build GPU state of their own.
        const BUILDS: [bool; GRAPH.len()] = [$(graph!(@builds $($field)?)),*];

        /// The GPU state of the passes of [`GRAPH`].
        pub(crate) struct Passes {
            $($(pub(crate) $field: $ty,)?)*
        }

        impl Passes {
            /// Builds each entry's state in the order of [`GRAPH`].
            pub(super) fn new(builder: &mut Builder) -> Result<Passes> {
                let mut i = 0;
                $(
                    $(
                        let end = (i + 1..GRAPH.len()).find(|&j| BUILDS[j]).unwrap_or(GRAPH.len());
                        builder.enter(&ENTRIES[i..end]);
                        let build = |$b: &mut Builder| -> Result<$ty> { $body };
                        let $field: $ty = build(&mut *builder)?;
                    )?
                    i += 1;
                )*
                let _ = i;
                Ok(Passes { $($($field,)?)* })
            }
        }
    };
    (@builds $field:ident) => { true };
    (@builds) => { false };
}

fn always(_: &Renderer) -> bool {
    true
}

graph! {
    build gbuffer: GBuffer = |b| {
        let c = b.c;
        let plain = !b.frame.has_cutouts();
        let g = GBuffer::new(b.gpu, (c.width, c.height, c.aa), &b.textures, &b.shared.tris, plain);
        b.write_view("gbuffer", &g.view)?;
        Ok(g)
    };
    pass FramePass {
        name: "gbuffer",
        tables: &[&crate::gpu::gbuffer::PASS],
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
    build surface: Option<SurfacePass> = |b| {
        // Every later pass reads the surface buffer; this pass fills it where textures or
        // vertex colours need it (else the passes use the triangle's).
        let buf = b.gpu.buffer(
            "surface",
            bytes::<Surface>(b.grid_pixels()),
            wgpu::BufferUsages::STORAGE,
        );
        let s = SurfacePass::new(
            b.gpu,
            &b.textures,
            &b.shared.params,
            &b.shared.tris,
            (b.view("gbuffer")?, &buf),
        );
        b.write("surface", &buf)?;
        Ok(s)
    };
    pass FramePass {
        name: "surface",
        tables: &[&crate::gpu::surface::PASS],
        files: "`gpu/surface.rs`, `shaders/surface.wgsl`",
        when: "scenes with textures or vertex colours",
        reads: &["gbuffer", "tris", "textures"],
        writes: &["surface"],
        what: "each sample's textured albedo and emission (the other scenes use the triangle's)",
        runs: |r| r.passes.surface.is_some(),
        encode: |r, enc, _| {
            let (gw, gh) = r.config.grid();
            if let Some(s) = &r.passes.surface {
                s.encode(enc, gw, gh);
            }
            Ok(())
        },
    },
    build shadows: ShadowMaps = |b| {
        let (c, f) = (b.c, b.frame);
        // Cut-outs and open single-sided triangles need each fragment's triangle.
        let per_triangle = f.has_cutouts()
            || f.sides()
                .is_some_and(|s| s.contains(&crate::scene::Sides::OPEN));
        let s = ShadowMaps::new(
            b.gpu,
            (c.shadow_size, c.light_samples),
            (f.tris.len() as u32, per_triangle),
            &b.textures,
            &b.shared.tris,
        );
        b.write_view("hemicubes", &s.array_view)?;
        Ok(s)
    };
    pass FramePass {
        name: "shadow_maps",
        tables: &[&crate::gpu::shadow::PASS],
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
    build direct: Direct = |b| {
        let sh = b.shared;
        let d = Direct::new(
            b.gpu,
            &sh.params,
            &sh.tris,
            &sh.lights,
            b.view("hemicubes")?,
            (b.view("gbuffer")?, b.buffer("surface")?),
            (b.grid_pixels(), b.frame),
        );
        b.write("direct", &d.output)?;
        Ok(d)
    };
    pass FramePass {
        name: "direct",
        tables: &[&crate::gpu::direct::PASS],
        files: "`gpu/direct.rs`, `shaders/direct.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "lights", "hemicubes"],
        writes: &["direct"],
        what: "direct light per sub-sample from the emitter samples (shared among a pixel's sub-samples for instant radiosity, all of them in each for a classical method: `split_light_samples`), with hemicube visibility, points on emitter triangles clamped as VPLs are when `--compensate` is on (`direct_clamp`); where no geometry is seen, the environment",
        runs: always,
        encode: |r, enc, f| {
            let (gw, gh) = r.config.grid();
            r.passes.direct.upload_camera(&r.gpu, f.view_proj);
            r.passes.direct.encode(enc, gw, gh);
            Ok(())
        },
    },
    build ism: Ism = |b| {
        let (c, sh) = (b.c, b.shared);
        let ism = Ism::new(
            b.gpu,
            &sh.params,
            &sh.tris,
            &sh.points,
            &sh.vpls,
            &sh.slots,
            c.slots,
            c.ism_size,
            c.pull_levels,
        );
        b.write("ism pyramid", &ism.pyramid)?;
        Ok(ism)
    };
    pass FramePass {
        name: "ism_splat",
        tables: &[&crate::gpu::ism::SPLAT],
        files: "`gpu/ism.rs`, `shaders/ism_splat.wgsl`",
        when: "always (only the slots whose VPL or geometry changed)",
        reads: &["tris", "points", "vpls", "slots"],
        writes: &["ism atlas"],
        what: "each redrawn slot's near-field cells, the plane each of its ray-cast points lies on, then its paraboloid tile: the nearest depth per texel of its subset of the point set (`atomicMax` on an inverted depth) but for points on their cell's plane",
        runs: always,
        encode: |r, enc, f| {
            let points = (r.config.ism_points, r.near_points(f.input));
            r.passes.ism.encode_splat(enc, f.changed_slots, points);
            Ok(())
        },
    },
    pass FramePass {
        name: "ism_pullpush",
        tables: &[&crate::gpu::ism::PULL_PUSH],
        files: "`gpu/ism.rs`, `shaders/ism_pullpush.wgsl`",
        when: "always (only the redrawn slots)",
        reads: &["ism atlas"],
        writes: &["ism pyramid"],
        what: "holes filled within each tile up to 2^levels texels (levels 0 and 1 of the pyramid); tiles of at most 64 texels in one fused dispatch that also empties the atlas",
        runs: always,
        encode: |r, enc, f| {
            r.passes.ism.encode_pull_push(enc, f.changed_slots);
            Ok(())
        },
    },
    build gather: Gather = |b| {
        let sh = b.shared;
        let g = Gather::new(
            b.gpu,
            &sh.params,
            &sh.tris,
            &sh.vpls,
            b.buffer("ism pyramid")?,
            (b.view("gbuffer")?, b.buffer("surface")?),
            b.grid_pixels(),
        );
        b.write("indirect", &g.output)?;
        Ok(g)
    };
    pass FramePass {
        name: "gather",
        tables: &[&crate::gpu::gather::PASS],
        files: "`gpu/gather.rs`, `shaders/gather.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "vpls", "ism pyramid"],
        writes: &["indirect"],
        what: "the indirect light per pixel: the sum over the VPLs (with `--interleave n > 1`, over the pixel's subset of them, times n^2) with ISM visibility; supersampled, once per pixel without the albedo",
        runs: always,
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            r.passes.gather.encode(enc, (iw, ih), r.config.interleave);
            Ok(())
        },
    },
    build interleave: Option<Interleave> = |b| {
        if b.c.interleave <= 1 {
            return Ok(None);
        }
        let i = Interleave::new(
            b.gpu,
            &b.shared.params,
            &b.shared.tris,
            (b.view("gbuffer")?, b.buffer("surface")?),
            b.buffer("indirect")?,
            b.grid_pixels(),
        );
        b.write("indirect", &i.output)?;
        Ok(Some(i))
    };
    pass FramePass {
        name: "interleave",
        tables: &[&crate::gpu::interleave::PASS],
        files: "`gpu/interleave.rs`, `shaders/interleave.wgsl`",
        when: "`--interleave n > 1`",
        reads: &["gbuffer", "surface", "tris", "indirect"],
        writes: &["indirect"],
        what: "the depth- and normal-aware mean of the subsets over the pixel's block (docs/math.md)",
        runs: |r| r.passes.interleave.is_some(),
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            if let Some(p) = &r.passes.interleave {
                p.encode(enc, iw, ih);
            }
            Ok(())
        },
    },
    build temporal: Option<Temporal> = |b| {
        let c = b.c;
        if c.accumulate <= 1 {
            return Ok(None);
        }
        // The pixels' samples are tile 0's: rows 0..height of the grid.
        let tile0 = c.grid().0 as u64 * c.height as u64;
        check_size(
            &b.gpu.limits,
            &format!("the history of {}x{} samples (`accumulate`)", c.grid().0, c.height),
            bytes::<HistorySample>(tile0),
            "lower `size` or `aa`, or drop `accumulate`",
        )?;
        let t = Temporal::new(
            b.gpu,
            (&b.shared.params, &b.shared.tris),
            b.view("gbuffer")?,
            b.buffer("indirect")?,
            tile0,
            (c.accumulate, c.history),
        );
        b.write("indirect", &t.output)?;
        Ok(Some(t))
    };
    pass FramePass {
        name: "temporal",
        tables: &[&crate::gpu::temporal::PASS],
        files: "`gpu/temporal.rs`, `shaders/temporal.wgsl`",
        when: "`--accumulate N > 1`",
        reads: &["gbuffer", "tris", "indirect", "history", "light gradient"],
        writes: &["indirect", "history"],
        what: "the indirect light as the running mean of up to N frames' estimates of the pixel's surface point; under a moving light or object the history weighed by the light's temporal gradient (`--history`)",
        runs: |r| r.passes.temporal.is_some(),
        encode: |r, enc, _| {
            let (iw, ih) = r.indirect_size();
            if let Some(t) = &mut r.passes.temporal {
                t.encode(enc, iw, ih);
            }
            Ok(())
        },
    },
    build compose: Compose = |b| {
        let supersampled = b.c.aa > 1;
        let p = Compose::new(
            b.gpu,
            &b.shared.params,
            &b.shared.tris,
            (b.view("gbuffer")?, b.buffer("surface")?),
            (b.buffer("direct")?, b.buffer("indirect")?),
            b.grid_pixels(),
            supersampled,
        );
        b.write("hdr", &p.hdr)?;
        b.write("ldr", &p.ldr)?;
        if supersampled {
            b.write("indirect sub-samples", &p.indirect_ss)?;
        }
        Ok(p)
    };
    pass FramePass {
        name: "compose",
        tables: &[&crate::gpu::compose::PASS],
        files: "`gpu/compose.rs`, `shaders/compose.wgsl`",
        when: "always",
        reads: &["gbuffer", "surface", "tris", "direct", "indirect"],
        writes: &["hdr", "ldr", "indirect sub-samples"],
        what: "emission + direct + indirect (linear), and the 8-bit preview; supersampled, each sub-sample's indirect light from its pixel's, times its albedo (`indirect sub-samples`), and no preview",
        runs: always,
        encode: |r, enc, _| {
            let (gw, gh) = r.config.grid();
            r.passes.compose.encode(enc, gw, gh);
            Ok(())
        },
    },
    build downsample: Option<Downsample> = |b| {
        let c = b.c;
        if c.aa <= 1 {
            return Ok(None);
        }
        let d = Downsample::new(
            b.gpu,
            &b.shared.params,
            (
                b.buffer("hdr")?,
                b.buffer("direct")?,
                b.buffer("indirect sub-samples")?,
            ),
            c.width as u64 * c.height as u64,
        );
        for (name, buf) in [
            ("hdr", &d.hdr),
            ("ldr", &d.ldr),
            ("direct", &d.direct),
            ("indirect", &d.indirect),
        ] {
            b.write(name, buf)?;
        }
        Ok(Some(d))
    };
    pass FramePass {
        name: "downsample",
        tables: &[&crate::gpu::downsample::PASS],
        files: "`gpu/downsample.rs`, `shaders/downsample.wgsl`",
        when: "`--aa S > 1`",
        reads: &["hdr", "direct", "indirect sub-samples"],
        writes: &["hdr", "ldr", "direct", "indirect"],
        what: "the box filter of each pixel's S^2 sub-samples",
        runs: |r| r.passes.downsample.is_some(),
        encode: |r, enc, _| {
            let c = &r.config;
            if let Some(p) = &r.passes.downsample {
                p.encode(enc, c.width, c.height);
            }
            Ok(())
        },
    },
}

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

    /// A pass's build may read only what its entry declares, and write what its entry or the
    /// entries sharing its state declare: the builder refuses the rest.
    #[test]
    fn builds_use_only_declared_resources() {
        use super::super::build::declared;
        let at = |name: &str| GRAPH.iter().position(|p| p.name == name).unwrap();
        let (splat, gather) = (at("ism_splat"), at("gather"));
        assert!(declared(&GRAPH[gather..gather + 1], "ism pyramid", "reads").is_ok());
        let e = declared(&GRAPH[gather..gather + 1], "hdr", "reads").unwrap_err();
        assert_eq!(
            e.to_string(),
            "the renderer's pass `gather` uses `hdr`, which its graph entry does not list in `reads`"
        );
        assert!(declared(&GRAPH[gather..gather + 1], "direct", "writes").is_err());
        // ism_splat's state is ism_pullpush's too: the pyramid is written by the pair.
        assert!(declared(&GRAPH[splat..splat + 1], "ism pyramid", "writes").is_err());
        assert!(declared(&GRAPH[splat..splat + 2], "ism pyramid", "writes").is_ok());
        // Exactly the entries with state of their own build (ism_pullpush shares splat's).
        let built: Vec<&str> = GRAPH
            .iter()
            .zip(BUILDS)
            .filter(|p| p.1)
            .map(|p| p.0.name)
            .collect();
        assert_eq!(built.len(), GRAPH.len() - 1);
        assert!(!built.contains(&"ism_pullpush"));
        // And each entry names its binding tables, which `gpu::bindings` checks.
        assert!(GRAPH.iter().all(|p| !p.tables.is_empty()));
    }

    /// Every pass reads only what an earlier pass (or the upload) wrote, and the names are
    /// unique: the order is a valid schedule.
    #[test]
    fn every_read_is_written_before() {
        let uploaded = [
            "vertices",
            "camera",
            "tris",
            "textures",
            "lights",
            "points",
            "vpls",
            "slots",
            "history",
            "light gradient",
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
