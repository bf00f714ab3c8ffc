//! CPU stages: BVH build, ray casting (closest hit and occlusion), light paths, reference.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Vec2, Vec3};
use irad::scene::builtin;
use irad::trace::Tracer;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let f = scene.at(0.0);
    c.bench_function("bvh_build/cornell", |b| {
        b.iter(|| Tracer::new(black_box(&f)))
    });
    let tr = Tracer::new(&f);
    let n = 4096u32;
    let dirs: Vec<Vec3> = (0..n)
        .map(|i| {
            f.camera.ray_dir(
                Vec2::new((i % 64) as f32 + 0.5, (i / 64) as f32 + 0.5),
                64,
                64,
            )
        })
        .collect();
    let mut g = c.benchmark_group("rays");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("closest_hit", |b| {
        b.iter(|| {
            dirs.iter()
                .filter(|&&d| tr.intersect(f.camera.position, d, f32::INFINITY).is_some())
                .count()
        })
    });
    let light = Vec3::new(0.0, 0.99, 0.01);
    let pts: Vec<Vec3> = dirs
        .iter()
        .filter_map(|&d| {
            tr.intersect(f.camera.position, d, 10.0)
                .map(|h| f.point(h.tri as usize, h.b1, h.b2))
        })
        .collect();
    g.bench_function("occlusion", |b| {
        b.iter(|| {
            pts.iter()
                .filter(|&&p| tr.occluded(p, (light - p).normalize(), light, Vec3::NEG_Y))
                .count()
        })
    });
    g.finish();
    let mut g = c.benchmark_group("light_paths");
    g.throughput(Throughput::Elements(1024));
    g.bench_function("1024_paths", |b| {
        b.iter(|| irad::vpl::trace_paths(&f, &tr, 1, 0, 1024))
    });
    g.finish();
    // Importance: every candidate against every camera point, one visibility ray each pair
    // that contributes (counted as pairs).
    let points = irad::vpl::importance::camera_points(&f, &tr, 256, 256, 256, 1);
    let cands = irad::vpl::trace_paths(&f, &tr, 1, 0, 400);
    let mut g = c.benchmark_group("importance");
    g.throughput(Throughput::Elements((cands.len() * points.len()) as u64));
    g.bench_function(
        format!("{}_vpls_x_{}_points", cands.len(), points.len()),
        |b| b.iter(|| irad::vpl::importance::importance_all(&cands, &points, &tr, 0.07)),
    );
    g.finish();
    // One sampler step of each kind at 256 slots, 1024 candidates, 256 camera points.
    use irad::vpl::sampler::{Sampler, SamplerKind, SamplerParams};
    let params = |kind| SamplerParams {
        kind,
        slots: 256,
        candidates: 1024,
        clamp: 0.07,
        seed: 1,
        width: 256,
        height: 256,
        knobs: irad::vpl::sampler::knobs::SamplerKnobs {
            camera_points: 256,
            eps: Some(0.05),
            mh_rate: 1.0,
            mh_follow: 0.0,
            mh_escape: 0,
            smc_rate: 0.05,
            smc_follow: 0.0,
            ..Default::default()
        },
    };
    let mut g = c.benchmark_group("sampler_step");
    for kind in [SamplerKind::Uniform, SamplerKind::Cdf, SamplerKind::Mh] {
        let mut s = Sampler::new(params(kind));
        s.select(&f, &tr, 0);
        let mut frame_index = 1;
        g.bench_function(format!("{kind:?}").to_lowercase(), |b| {
            b.iter(|| {
                frame_index += 1;
                s.select(&f, &tr, frame_index)
            })
        });
    }
    g.finish();
    let s = irad::reference::ReferenceSettings {
        width: 32,
        height: 32,
        spp: 4,
        seed: 1,
        ..Default::default()
    };
    let mut g = c.benchmark_group("reference");
    g.throughput(Throughput::Elements(32 * 32 * 4));
    g.bench_function("32x32x4spp", |b| {
        b.iter(|| irad::reference::render(&f, &tr, &s, &|| {}))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
