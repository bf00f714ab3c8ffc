//! The Cornell box's floor meshed for classical radiosity, seen from above: adaptive meshing
//! against discontinuity meshing (the shadow and penumbra boundaries cut into the elements,
//! drawn red), each element filled with its solved radiance (progressive refinement,
//! reflected light). Writes docs/radiosity-floor.png (or the path given).
//!
//! `cargo run --release --example discontinuity_floor [OUT.png]`

use glam::Vec3;
use irad::radiosity::{self, discontinuity, Meshing, Part, RadiositySettings};
use irad::scene::builtin;
use irad::trace::Tracer;
use plotters::prelude::*;

#[allow(clippy::needless_range_loop)]
fn main() -> anyhow::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "docs/radiosity-floor.png".into());
    let frame = builtin::load("cornell")
        .expect("built-in")
        .expect("built-in")
        .at(0.0);
    let tracer = Tracer::new(&frame);
    let lines = discontinuity::lines(&frame, &tracer, 0.15);
    let floor = |p: Vec3| p.y < -0.999;
    let panels = [Meshing::Adaptive, Meshing::Discontinuity];
    let _ = plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        include_bytes!("../assets/DejaVuSans.ttf"),
    );
    let (w, h) = (1500u32, 520u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let areas = root.split_evenly((1, 3));
        for (area, meshing) in areas.iter().zip(panels) {
            let s = RadiositySettings {
                meshing,
                ..Default::default()
            };
            let sol = radiosity::solve(&frame, &tracer, &s);
            let v = sol.display_values(Part::Reflected);
            let max = v
                .iter()
                .map(|c| irad::math::luminance(*c))
                .fold(0.0f32, f32::max)
                .max(1e-6);
            let title = format!(
                "{:?}: {} elements ({} lines cut)",
                meshing, sol.stats.elements, sol.stats.discontinuities
            );
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 18))
                .margin(10)
                .build_cartesian_2d(-1.0f32..1.0f32, -1.0f32..1.0f32)?;
            for i in 0..sol.mesh.len() {
                let c = sol.mesh.corners(i);
                if !c.iter().all(|&p| floor(p)) {
                    continue;
                }
                let g = (255.0 * (irad::math::luminance(v[i]) / max).powf(0.5)) as u8;
                let pts: Vec<(f32, f32)> = c.iter().map(|p| (p.x, p.z)).collect();
                chart.draw_series(std::iter::once(Polygon::new(
                    pts.clone(),
                    RGBColor(g, g, g),
                )))?;
                let mut ring = pts.clone();
                ring.push(pts[0]);
                chart.draw_series(std::iter::once(PathElement::new(
                    ring,
                    RGBColor(90, 120, 200).stroke_width(1),
                )))?;
            }
            if meshing == Meshing::Discontinuity {
                for l in lines.iter().filter(|l| floor(l.a) && floor(l.b)) {
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(l.a.x, l.a.z), (l.b.x, l.b.z)],
                        RED.stroke_width(1),
                    )))?;
                }
            }
        }
        {
            let mut chart = ChartBuilder::on(&areas[2])
                .caption(
                    "seen fraction of the light, and the lines",
                    ("sans-serif", 18),
                )
                .margin(10)
                .build_cartesian_2d(-1.0f32..1.0f32, -1.0f32..1.0f32)?;
            let k = 200;
            let cells: Vec<(f32, f32, f32)> = (0..k * k)
                .map(|i| {
                    let (x, z) = (
                        -1.0 + 2.0 * ((i % k) as f32 + 0.5) / k as f32,
                        -1.0 + 2.0 * ((i / k) as f32 + 0.5) / k as f32,
                    );
                    (
                        x,
                        z,
                        seen_fraction(&frame, &tracer, Vec3::new(x, -0.999, z)),
                    )
                })
                .collect();
            let h = 1.0 / k as f32;
            chart.draw_series(cells.iter().map(|&(x, z, f)| {
                let g = (255.0 * f) as u8;
                Rectangle::new([(x - h, z - h), (x + h, z + h)], RGBColor(g, g, g).filled())
            }))?;
            for l in lines.iter().filter(|l| floor(l.a) && floor(l.b)) {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(l.a.x, l.a.z), (l.b.x, l.b.z)],
                    RED.stroke_width(1),
                )))?;
            }
        }
        root.present()?;
    }
    image::RgbImage::from_raw(w, h, buf)
        .expect("buffer size")
        .save(&out)?;
    println!(
        "{} lines ({} on the floor); wrote {out}",
        lines.len(),
        lines.iter().filter(|l| floor(l.a) && floor(l.b)).count()
    );
    Ok(())
}

/// The fraction of the emitters' unoccluded irradiance that reaches floor point `x`, by
/// 16x16 stratified points on each emitting triangle.
fn seen_fraction(frame: &irad::scene::Frame, tracer: &Tracer, x: Vec3) -> f32 {
    let n = Vec3::Y;
    let (mut seen, mut all) = (0.0f32, 0.0f32);
    for (i, t) in frame.tris.iter().enumerate() {
        if frame.emission(i).max_element() <= 0.0 {
            continue;
        }
        let ne = frame.normals[i];
        for a in 0..16 {
            for b in 0..16 {
                let (mut u, mut v) = ((a as f32 + 0.5) / 16.0, (b as f32 + 0.5) / 16.0);
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let y = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                let d = y - x;
                let r2 = d.length_squared();
                let g = (n.dot(d) * -ne.dot(d)).max(0.0) / (r2 * r2);
                all += g;
                if g > 0.0 && !tracer.occluded(x, n, y, ne) {
                    seen += g;
                }
            }
        }
    }
    if all > 0.0 {
        seen / all
    } else {
        0.0
    }
}
