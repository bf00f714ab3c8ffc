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
    let s = irad::reference::Settings {
        width: 32,
        height: 32,
        spp: 4,
        seed: 1,
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
