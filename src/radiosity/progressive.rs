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
}

pub fn solve(frame: &Frame, tracer: &Tracer, mesh: Mesh, p: &ProgressiveSettings) -> Solution {
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
    while emitted > 0.0 && stats.iterations < p.max_shots {
        // The shooter: largest unshot power.
        let (s, power) = (0..n)
            .map(|i| (i, area[i] * luminance(unshot_e[i] + unshot_r[i])))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        left = (0..n)
            .map(|i| area[i] * luminance(unshot_e[i] + unshot_r[i]))
            .sum();
        if left <= p.tolerance * emitted || power <= 0.0 {
            break;
        }
        let q = if power >= 0.01 * emitted {
            p.bright
        } else {
            p.dim
        };
        let (cs, ns) = (corners[s], normals[s]);
        let ff: Vec<(f32, u32)> = (0..n)
            .into_par_iter()
            .map(|j| {
                if j == s || rho[j].max_element() <= 0.0 {
                    (0.0, 0)
                } else {
                    form_factor::between(&corners[j], normals[j], &cs, ns, Some(tracer), q)
                }
            })
            .collect();
        let (ue, ur) = (unshot_e[s], unshot_r[s]);
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
        unshot_e[s] = Vec3::ZERO;
        unshot_r[s] = Vec3::ZERO;
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
        };
        let sol = solve(&f, &tr, mesh.clone(), &p);
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
        };
        let sol = solve(&f, &tr, mesh, &p);
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
