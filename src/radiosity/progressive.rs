//! Progressive refinement (Cohen, Chen, Wallace, Greenberg 1988): every element starts with
//! its emission as unshot radiance; the element with the largest unshot power `A_i dL_i`
//! shoots it to every element `j`, which receives `rho_j dL_i F_ji` (the form factor from the
//! receiver to the shooter, so `F_ij A_i / A_j` of the lecture is evaluated at the receiver's
//! points, exactly and with visibility rays), adds it to its radiance and to its own unshot
//! radiance. The shooter's unshot radiance goes to zero. It stops when the unshot power falls
//! under `tolerance` times the source power; until then the ambient term stands in for what
//! is left. The punctual lights' direct light (no element emits it) starts as reflected
//! unshot radiance: its first shot is already indirect light.

use super::form_factor::{self, FormFactorAccuracy};
use super::mesh::Mesh;
use super::{ambient, element_materials, punctual_direct, Solution, Stats};
use crate::math::luminance;
use crate::scene::Frame;
use crate::trace::Tracer;
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug)]
pub struct ProgressiveSettings {
    /// Stop when the unshot power is under this fraction of the source power (emitted plus
    /// the punctual lights' direct light).
    pub tolerance: f32,
    pub max_shots: usize,
    /// Form-factor quality for shots carrying at least 1% of the emitted power.
    pub bright: FormFactorAccuracy,
    /// ... and for the dimmer shots that follow.
    pub dim: FormFactorAccuracy,
    /// Dim shots come from the mesh's patches (every element of the patch with the most
    /// unshot power shoots their area-weighted mean at once) instead of single elements.
    pub dim_from_patches: bool,
}

/// Solves on `mesh`, telling `progress` the fraction done (see [`super::convergence`]) after
/// every shot.
pub fn solve(
    frame: &Frame,
    tracer: &Tracer,
    mesh: Mesh,
    p: &ProgressiveSettings,
    progress: &(dyn Fn(f32) + Sync),
) -> Solution {
    let start = std::time::Instant::now();
    let n = mesh.len();
    let (le, rho) = element_materials(frame, &mesh);
    let area: Vec<f32> = mesh.elems.iter().map(|e| e.area).collect();
    let corners: Vec<[Vec3; 3]> = (0..n).map(|e| mesh.corners(e)).collect();
    let normals: Vec<Vec3> = mesh.elems.iter().map(|e| e.normal).collect();
    // The punctual lights' direct light: all zero without them (then everything below is
    // as for emitters alone).
    let (lp, rays) = punctual_direct(frame, tracer, &mesh, &rho);
    let mut radiance: Vec<Vec3> = (0..n).map(|i| le[i] + lp[i]).collect();
    let mut direct = lp.clone();
    // Unshot radiance still to go: emitted (direct light when it lands) and reflected.
    let mut unshot_e = le.clone();
    let mut unshot_r = lp;
    let emitted: f32 = (0..n)
        .map(|i| area[i] * luminance(le[i] + unshot_r[i]))
        .sum();
    let mut stats = Stats {
        method: "progressive".into(),
        elements: n,
        rays,
        ..Default::default()
    };
    let mut left = emitted;
    // Each patch's elements, and a scratch sum of unshot power per patch.
    let mut members = vec![Vec::new(); mesh.patches.len()];
    for (i, e) in mesh.elems.iter().enumerate() {
        members[e.patch as usize].push(i);
    }
    let mut patch_power = vec![0.0f32; mesh.patches.len()];
    while emitted > 0.0 && stats.iterations < p.max_shots {
        let power: Vec<f32> = (0..n)
            .map(|i| area[i] * luminance(unshot_e[i] + unshot_r[i]))
            .collect();
        left = power.iter().sum();
        // The shooter: the element of largest unshot power while shots are bright, then
        // (with patches) the patch of largest unshot power.
        let (s, top) = power
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        if left <= p.tolerance * emitted || top <= 0.0 {
            break;
        }
        progress(super::convergence(left, emitted, p.tolerance));
        // A signal stops the solve (the command drops the frame in flight).
        if crate::interrupt::requested() {
            break;
        }
        let bright = top >= 0.01 * emitted;
        let q = if bright { p.bright } else { p.dim };
        let shooters: Vec<usize> = if bright || !p.dim_from_patches {
            vec![s]
        } else {
            for (i, e) in mesh.elems.iter().enumerate() {
                patch_power[e.patch as usize] += power[i];
            }
            let best = patch_power
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(k, _)| k);
            patch_power.iter_mut().for_each(|x| *x = 0.0);
            members[best].clone()
        };
        // What the shooter sends: its unshot radiance (a patch: area-weighted mean of its
        // elements'), from its triangle.
        let (cs, ns, ue, ur) = if let [one] = shooters[..] {
            (corners[one], normals[one], unshot_e[one], unshot_r[one])
        } else {
            let pa = &mesh.patches[mesh.elems[shooters[0]].patch as usize];
            let a: f32 = shooters.iter().map(|&i| area[i]).sum();
            let mean = |u: &[Vec3]| shooters.iter().map(|&i| u[i] * area[i]).sum::<Vec3>() / a;
            (pa.corners, pa.normal, mean(&unshot_e), mean(&unshot_r))
        };
        let ff: Vec<(f32, u32)> = (0..n)
            .into_par_iter()
            .map(|j| {
                if shooters.contains(&j) || rho[j].max_element() <= 0.0 {
                    (0.0, 0)
                } else {
                    form_factor::between(&corners[j], normals[j], &cs, ns, Some(tracer), q)
                }
            })
            .collect();
        for &s in &shooters {
            unshot_e[s] = Vec3::ZERO;
            unshot_r[s] = Vec3::ZERO;
        }
        for (j, &(f, rays)) in ff.iter().enumerate() {
            stats.rays += rays as u64;
            if f <= 0.0 {
                continue;
            }
            stats.form_factors += 1;
            let de = rho[j] * ue * f;
            let dr = rho[j] * ur * f;
            direct[j] += de;
            radiance[j] += de + dr;
            unshot_r[j] += de + dr;
        }
        stats.iterations += 1;
    }
    let unshot: Vec<Vec3> = (0..n).map(|i| unshot_e[i] + unshot_r[i]).collect();
    let amb = ambient(&mesh, &rho, &unshot);
    stats.residual = if emitted > 0.0 { left / emitted } else { 0.0 };
    stats.seconds = start.elapsed().as_secs_f64();
    Solution {
        mesh,
        radiance,
        emission: le,
        direct,
        ambient: amb,
        pointwise: None,
        stats,
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Gaussian elimination with partial pivoting (one right-hand side).
    fn gauss(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                .unwrap();
            a.swap(c, p);
            b.swap(c, p);
            for r in c + 1..n {
                let k = a[r][c] / a[c][c];
                for k2 in c..n {
                    a[r][k2] -= k * a[c][k2];
                }
                b[r] -= k * b[c];
            }
        }
        let mut x = vec![0.0; n];
        for r in (0..n).rev() {
            let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
            x[r] = (b[r] - s) / a[r][r];
        }
        x
    }

    #[test]
    fn converges_to_the_direct_solution_of_the_linear_system() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let mesh = Mesh::uniform(&f, 0.7, 10_000);
        let n = mesh.len();
        let q = FormFactorAccuracy { points: 3, rays: 4 };
        let p = ProgressiveSettings {
            tolerance: 1e-7,
            max_shots: 100_000,
            bright: q,
            dim: q,
            dim_from_patches: false,
        };
        let sol = solve(&f, &tr, mesh.clone(), &p, &|_| {});
        assert!(sol.stats.residual <= 1e-7);
        // The same form factors, as a matrix: (I - rho F) L = Le, per channel.
        let (le, rho) = element_materials(&f, &mesh);
        let ff: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| form_factor::element(&mesh, Some(&tr), i, j, q) as f64)
                    .collect()
            })
            .collect();
        let mut worst = 0.0f64;
        for c in 0..3 {
            let a: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| f64::from(i == j) - rho[i][c] as f64 * ff[i][j])
                        .collect()
                })
                .collect();
            let b: Vec<f64> = le.iter().map(|l| l[c] as f64).collect();
            let x = gauss(a, b);
            for i in 0..n {
                let got = sol.radiance[i][c] as f64;
                worst = worst.max((got - x[i]).abs() / x[i].abs().max(1e-3));
            }
        }
        // Measured: 1e-5 (f32 sums against f64 elimination).
        assert!(
            worst < 1e-4,
            "worst relative difference {worst} over {n} elements"
        );
    }

    #[test]
    fn white_furnace_is_two_and_energy_balances() {
        let f = builtin::load("furnace").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let mesh = Mesh::uniform(&f, 0.5, 10_000);
        let p = ProgressiveSettings {
            tolerance: 1e-3,
            max_shots: 1_000_000,
            bright: FormFactorAccuracy { points: 4, rays: 4 },
            dim: FormFactorAccuracy { points: 4, rays: 4 },
            dim_from_patches: false,
        };
        let sol = solve(&f, &tr, mesh, &p, &|_| {});
        // With the ambient term the unshot remainder is accounted for.
        let shown: Vec<Vec3> = (0..sol.radiance.len())
            .map(|i| sol.radiance[i] + sol.ambient[i])
            .collect();
        let worst = shown
            .iter()
            .map(|l| (*l - Vec3::splat(2.0)).abs().max_element())
            .fold(0.0, f32::max);
        // Measured: 0.02 (the form factors' row sums in a closed box are within 1.3% of 1).
        assert!(worst < 0.03, "worst {worst}");
        // Energy: emitted + reflected = leaving. Power reflected = rho * power received,
        // received = leaving - emitted over rho: check sum A (L - Le) = rho * sum A (L - unshot)
        // within the form factors' row-sum error.
        let a: f32 = sol.mesh.elems.iter().map(|e| e.area).sum();
        let leaving = sol.power(&sol.radiance).x / a;
        // In a closed box everything leaving arrives somewhere: L = Le + rho * (L - unshot).
        assert!((leaving - 2.0).abs() < 0.03, "mean radiance {leaving}");
    }
}

#[cfg(test)]
mod patch_tests {
    use super::*;
    use crate::scene::builtin;

    /// Dim shots from patches (each patch four element sizes across) give the solution that
    /// element-by-element shots give, in far fewer shots: the Cornell box at the default
    /// tolerance and form-factor accuracies.
    #[test]
    fn patch_shots_agree_with_element_shots_in_fewer_shots() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let mesh = Mesh::uniform_with_patches(&f, 1.2, 0.3, 6000);
        let settings = |dim_from_patches| ProgressiveSettings {
            tolerance: 1e-2,
            max_shots: usize::MAX,
            bright: FormFactorAccuracy { points: 4, rays: 7 },
            dim: FormFactorAccuracy { points: 1, rays: 4 },
            dim_from_patches,
        };
        let elements = solve(&f, &tr, mesh.clone(), &settings(false), &|_| {});
        let patches = solve(&f, &tr, mesh, &settings(true), &|_| {});
        let shown = |s: &Solution| s.display_values(crate::radiosity::Part::Reflected);
        let (a, b) = (shown(&elements), shown(&patches));
        let area = |i: usize| elements.mesh.elems[i].area;
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for i in 0..a.len() {
            let d = luminance(b[i]) - luminance(a[i]);
            num += (area(i) * d * d) as f64;
            den += (area(i) * luminance(a[i]).powi(2)) as f64;
        }
        let rel_mse = num / den;
        let bias = luminance(patches.power(&b)) / luminance(elements.power(&a)) - 1.0;
        println!(
            "{} elements, {} patches: shots {} -> {}, relMSE {rel_mse:.5}, bias {bias:+.4}",
            a.len(),
            patches.mesh.patches.len(),
            elements.stats.iterations,
            patches.stats.iterations
        );
        // Measured: 1750 elements in 122 patches, 4973 shots -> 355, relMSE 0.00078 and
        // bias -0.8% per element between the two.
        assert!(rel_mse < 0.0015, "relMSE {rel_mse}");
        assert!(bias.abs() < 0.012, "bias {bias}");
        assert!(
            patches.stats.iterations * 4 < elements.stats.iterations,
            "shots {} against {}",
            patches.stats.iterations,
            elements.stats.iterations
        );
    }
}
