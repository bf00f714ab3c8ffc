//! Classical radiosity on a scene against the path-traced reference: solves with each
//! method, renders the CPU display (radiosity for all reflected light, and radiosity for the
//! indirect part with traced direct light) and prints relMSE, solve seconds and counts.
//!
//! `cargo run --release --example radiosity_cornell -- [scene] [size] [spp] [reference.exr]`
//! The reference is rendered (and written to the given path) when the file is missing.

use irad::image::Hdr;
use irad::metrics::frame_error;
use irad::radiosity::{self, display, Part, RadiositySettings, Solver};
use irad::reference;
use irad::scene::builtin;
use irad::trace::Tracer;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene = args.get(1).map_or("cornell", |s| s.as_str());
    let size: u32 = args.get(2).map_or(Ok(256), |s| s.parse())?;
    let spp: u32 = args.get(3).map_or(Ok(1024), |s| s.parse())?;
    let ref_path = args
        .get(4)
        .cloned()
        .unwrap_or(format!("/tmp/irad-ref-{scene}-{size}-{spp}.exr"));
    let methods: Vec<Solver> = std::env::var("METHODS")
        .unwrap_or("progressive,hierarchical,stochastic".into())
        .split(',')
        .map(|m| match m {
            "hierarchical" => Solver::Hierarchical,
            "stochastic" => Solver::Stochastic,
            _ => Solver::Progressive,
        })
        .collect();
    let s = builtin::load_any(scene)?;
    let f = s.at(0.0);
    let tr = Tracer::new(&f);
    let path = std::path::Path::new(&ref_path);
    let reference = if path.exists() {
        Hdr::read(path)?
    } else {
        let t = std::time::Instant::now();
        let img = reference::render(
            &f,
            &tr,
            &reference::ReferenceSettings {
                width: size,
                height: size,
                spp,
                seed: 1,
                ..Default::default()
            },
            &|| {},
        );
        img.write_exr(path)?;
        eprintln!("reference {spp} spp: {:.1} s", t.elapsed().as_secs_f64());
        img
    };
    let element_size: f32 = std::env::var("ELEMENT").map_or(Ok(0.15), |s| s.parse())?;
    let max_elements: usize = std::env::var("MAX_ELEMENTS").map_or(Ok(6000), |s| s.parse())?;
    let rays: usize = std::env::var("RAYS").map_or(Ok(400_000), |s| s.parse())?;
    let tolerance: f32 = std::env::var("TOLERANCE").map_or(Ok(1e-2), |s| s.parse())?;
    let out = std::env::var("OUT").ok();
    println!("method        part       relMSE   rel_bias  elements  links     iters  rays        solve_s");
    for m in methods {
        let settings = RadiositySettings {
            solver: m,
            element_size,
            max_elements,
            rays,
            tolerance,
            ..RadiositySettings::default()
        };
        let sol = radiosity::solve(&f, &tr, &settings);
        for part in [Part::Reflected, Part::Indirect] {
            let shaded = display::Shaded::new(&f, &sol, part);
            let img = display::render_cpu(
                &f,
                &tr,
                &shaded,
                &display::DisplayView {
                    width: size,
                    height: size,
                    spp: 4,
                    light_samples: 64,
                    seed: 1,
                },
            );
            let e = frame_error(&img, &reference)?;
            if let Some(dir) = &out {
                img.write_exr(
                    &std::path::Path::new(dir).join(format!("{}-{part:?}.exr", m.name())),
                )?;
            }
            let st = &sol.stats;
            println!(
                "{:<13} {:<10} {:<8.5} {:<9.4} {:<9} {:<9} {:<6} {:<11} {:.2}",
                m.name(),
                format!("{part:?}"),
                e.rel_mse,
                e.rel_bias,
                st.elements,
                st.links,
                st.iterations,
                st.rays,
                st.seconds
            );
        }
    }
    Ok(())
}
