//! Classical radiosity through the GPU display pass, held to its CPU twin on every adapter
//! found (lavapipe through Vulkan, llvmpipe through GL).

use crate::common::{self, backends};
use irad::gpu::radiosity::RadiosityPass;
use irad::gpu::Gpu;
use irad::metrics::frame_error;
use irad::radiosity::{self, display, Part, RadiositySettings, Solver};
use irad::scene::builtin;
use irad::trace::Tracer;

#[test]
fn gpu_display_matches_the_cpu_twin() {
    let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
    let tr = Tracer::new(&f);
    let sol = radiosity::solve(
        &f,
        &tr,
        &RadiositySettings {
            solver: Solver::Progressive,
            element_size: 0.3,
            refine_rounds: 0,
            tolerance: 0.02,
            ..RadiositySettings::default()
        },
    );
    let shaded = display::Shaded::new(&f, &sol, Part::Reflected);
    let (w, h) = (96, 96);
    let cpu = display::render_cpu(
        &f,
        &tr,
        &shaded,
        &display::DisplayView {
            width: w,
            height: h,
            spp: 0,
            light_samples: 0,
            seed: 1,
        },
    );
    let mut tested = 0;
    for b in backends() {
        let gpu = Gpu::new(b).unwrap();
        let mut pass = RadiosityPass::new(&gpu, w, h);
        pass.upload(&gpu, &shaded);
        let img = pass.render(&gpu, &f).unwrap();
        let e = frame_error(&img, &cpu).unwrap();
        // Measured on lavapipe and llvmpipe: relMSE 7.8e-4 (element edges falling on either
        // side of a pixel centre), relative bias -3.3e-4 (-1.7e-4 on the mesh before
        // progressive refinement meshed patches first).
        println!("{b:?}: {e:?}");
        if e.rel_mse > 1.2e-3 || e.rel_bias.abs() > 5e-4 {
            let name = format!("display-{b:?}").to_lowercase();
            let images = common::save_images("radiosity", &name, &img, &cpu);
            panic!("{b:?}: {e:?} ({images})");
        }
        tested += 1;
    }
    assert!(tested > 0, "no usable Vulkan or GL adapter");
}
