use super::{
    coefficients, next_smooth3, rectangle_integrals, single_body, strip, tangential_kernel_product,
    tangential_kernel_product_plain, Complex, Complex64, Convolver, FftNum,
};
#[test]
fn centre_of_uniform_square_matches_love() {
    // Love (1929)/Johnson eq. 3.25: centre of a square of side 2c under pressure p:
    // ∬1/r = 8 c asinh(1) = 4c·2 ln(1+√2).
    let c = 1e-3;
    let (i1, ixx, iyy, ixy) = rectangle_integrals(0.0, 0.0, c, c);
    assert!((i1 - 8.0 * c * (1.0_f64).asinh()).abs() < 1e-15);
    assert!((ixx - iyy).abs() < 1e-18 && ixy.abs() < 1e-18);
    // far field: ∬1/r → area / distance
    let (f1, fxx, _, fxy) = rectangle_integrals(1.0, 0.5, c, c);
    let r = (1.25_f64).sqrt();
    let area = 4.0 * c * c;
    assert!((f1 / (area / r) - 1.0).abs() < 1e-5);
    assert!((fxx / (area / r.powi(3)) - 1.0).abs() < 1e-5);
    assert!((fxy / (area * 0.5 / r.powi(3)) - 1.0).abs() < 1e-5);
}

#[test]
fn fft_products_equal_dense_products() {
    // Independent check: dense double sum of the closed-form coefficients; nx = 7 pads to
    // 15 rows (odd), nx = 8 to exactly 2nx = 16 (the extended row's xy coupling from
    // source row 0 added directly), nx = 12 to 24
    for nx in [7, 8, 12] {
        fft_products_equal_dense_products_on(nx);
    }
}

fn fft_products_equal_dense_products_on(nx: usize) {
    let (ny, dx, dy) = (5, 0.3e-3, 0.45e-3);
    let (es, g, nu) = (115e9, 80e9, 0.3);
    let mut conv = Convolver::new(nx, ny, dx, dy, es, g, nu);
    let n = nx * ny;
    let p: Vec<f64> = (0..n).map(|k| ((k * 7919) % 13) as f64 * 1e6).collect();
    let q: Vec<f64> = (0..n)
        .map(|k| ((k * 104729) % 11) as f64 * 1e6 - 5e6)
        .collect();
    let mut u = vec![0.0; n];
    conv.normal(&p, &mut u);
    let (mut ux, mut uy) = (vec![0.0; n], vec![0.0; n]);
    for shift in 0..2 {
        conv.tangential(&p, &q, &mut ux, &mut uy, shift);
        for i in 0..nx {
            for j in 0..ny {
                let (mut dz, mut dxv, mut dyv) = (0.0, 0.0, 0.0);
                for k in 0..nx {
                    for l in 0..ny {
                        let ox = (i as f64 + shift as f64 - k as f64) * dx;
                        let oy = (j as f64 - l as f64) * dy;
                        let c = coefficients(ox, oy, dx, dy, es, g, nu);
                        let s = k * ny + l;
                        dz += c.zz * p[s];
                        dxv += c.xx * p[s] + c.xy * q[s];
                        dyv += c.xy * p[s] + c.yy * q[s];
                    }
                }
                let e = i * ny + j;
                if shift == 0 {
                    assert!((u[e] - dz).abs() < 1e-12 * dz.abs().max(1e-9));
                }
                assert!(
                    (ux[e] - dxv).abs() < 1e-10 * dxv.abs().max(1e-9),
                    "{} {}",
                    ux[e],
                    dxv
                );
                assert!(
                    (uy[e] - dyv).abs() < 1e-10 * dyv.abs().max(1e-9),
                    "{} {}",
                    uy[e],
                    dyv
                );
            }
        }
    }
}

#[test]
fn box_products_equal_dense_sums() {
    // Independent check: dense double sum of the closed-form coefficients over a traction
    // confined to a box; odd and even box extents (padded sizes 15 × 9, 27 × 5, 16 × 16
    // on the 24 × 10 and 16 × 9 grids: single precision), and a box as large as the grid
    // (the whole grid's double-precision path)
    let (dx, dy) = (0.3e-3, 0.45e-3);
    let (es, g, nu) = (115e9, 80e9, 0.3);
    for &(nx, ny, (r0, r1), (c0, c1)) in &[
        (24usize, 10usize, (3usize, 11usize), (2usize, 7usize)),
        (24, 10, (5, 19), (4, 7)),
        (16, 9, (0, 8), (0, 8)),
        (16, 9, (0, 16), (0, 9)),
    ] {
        let mut conv = Convolver::new(nx, ny, dx, dy, es, g, nu);
        let n = nx * ny;
        let inside = |k: usize| (r0..r1).contains(&(k / ny)) && (c0..c1).contains(&(k % ny));
        let tx: Vec<f64> = (0..n)
            .map(|k| {
                if inside(k) {
                    ((k * 7919) % 13) as f64 * 1e6
                } else {
                    0.0
                }
            })
            .collect();
        let ty: Vec<f64> = (0..n)
            .map(|k| {
                if inside(k) {
                    ((k * 104729) % 11) as f64 * 1e6 - 5e6
                } else {
                    0.0
                }
            })
            .collect();
        // a box on a smaller padded grid is a single-precision product: bound its error
        // by f32 rounding (Higham 2002 Thm 24.2: a radix-2 FFT's error is at most
        // about log2 N · u · ‖x‖₂ per pass; forward, kernel product, inverse, and the
        // rounding of the tractions), with the operator's norm ≤ λ_max
        let (p1, p2) = (
            next_smooth3(2 * (r1 - r0) - 1),
            next_smooth3(2 * (c1 - c0) - 1),
        );
        let single = conv.boxes.iter().any(|b| (b.m1, b.m2) == (p1, p2));
        let norm = tx.iter().chain(&ty).map(|v| v * v).sum::<f64>().sqrt();
        let f32_bound =
            10.0 * ((p1 * p2) as f64).log2() * f64::from(f32::EPSILON) * conv.lambda_max_t * norm;
        let (mut ux, mut uy) = (vec![f64::NAN; n], vec![f64::NAN; n]);
        for _ in 0..2 {
            // the second pass reuses the kept spectra of the padded size
            conv.tangential_box(&tx, &ty, &mut ux, &mut uy, (r0, r1), (c0, c1));
            for e in (r0 * ny)..(r1 * ny) {
                let (i, j) = (e / ny, e % ny);
                let (mut sx, mut sy) = (0.0, 0.0);
                if inside(e) {
                    for s in (0..n).filter(|&s| inside(s)) {
                        let ox = (i as f64 - (s / ny) as f64) * dx;
                        let oy = (j as f64 - (s % ny) as f64) * dy;
                        let c = coefficients(ox, oy, dx, dy, es, g, nu);
                        sx += c.xx * tx[s] + c.xy * ty[s];
                        sy += c.xy * tx[s] + c.yy * ty[s];
                    }
                }
                let scale = if single {
                    f32_bound
                } else {
                    1e-10 * sx.abs().max(sy.abs()).max(1e-9)
                };
                assert!(
                    (ux[e] - sx).abs() < scale && (uy[e] - sy).abs() < scale,
                    "{nx}x{ny} box {r0}..{r1} × {c0}..{c1}, element {e}: ({}, {}) vs ({sx}, {sy})",
                    ux[e],
                    uy[e]
                );
            }
        }
    }
}

#[test]
fn kernel_product_dispatch_gives_the_bits_of_the_plain_loop() {
    // the run-time dispatched product (AVX2 where the CPU has it)
    // against the plain loop, bit for bit, in both precisions, on odd and even spectral
    // grids (rows shorter and longer than a vector, every remainder); and against the
    // formula written out
    for &(m1, m2) in &[
        (48usize, 36usize),
        (15, 9),
        (64, 48),
        (4, 3),
        (6, 5),
        (7, 2),
    ] {
        kernel_product_case::<f64>(m1, m2, 1e-14);
        kernel_product_case::<f32>(m1, m2, 1e-5);
    }
}

/// [`kernel_product_dispatch_gives_the_bits_of_the_plain_loop`] in precision `T` on an
/// `m1 × m2` grid; `tol` the formula's relative tolerance.
fn kernel_product_case<T: FftNum + From<f32> + Into<f64>>(m1: usize, m2: usize, tol: f64) {
    let n = m1 * m2;
    let val = |k: usize, s: usize| T::from(((k * s) % 1009) as f32 / 97.0 - 5.0);
    let z: Vec<Complex<T>> = (0..n)
        .map(|k| Complex::new(val(k, 7919), val(k, 104729)))
        .collect();
    let ka: Vec<T> = (0..n).map(|k| val(k, 31)).collect();
    let kb: Vec<Complex<T>> = (0..n)
        .map(|k| Complex::new(val(k, 17), val(k, 53)))
        .collect();
    let zero = Complex::new(T::from(0.0), T::from(0.0));
    let (mut w, mut w_plain) = (vec![zero; n], vec![zero; n]);
    tangential_kernel_product(&z, &ka, &kb, &mut w, m1, m2);
    tangential_kernel_product_plain(&z, &ka, &kb, &mut w_plain, m1, m2);
    let c64 = |c: Complex<T>| Complex64::new(c.re.into(), c.im.into());
    for q in 0..n {
        let bits = |c: Complex<T>| (c64(c).re.to_bits(), c64(c).im.to_bits());
        assert_eq!(bits(w[q]), bits(w_plain[q]), "{m1}x{m2} {q}");
        let (k2, k1) = (q / m1, q % m1);
        let mq = ((m2 - k2) % m2) * m1 + (m1 - k1) % m1;
        let e = c64(z[q]) * ka[q].into() + c64(kb[q]) * c64(z[mq]).conj();
        assert!(
            (c64(w[q]) - e).norm() <= tol * e.norm().max(1.0),
            "{m1}x{m2} {q}"
        );
    }
}

/// Dense double sum `Σ_j C_zz(i − j) p_j` of the closed-form coefficients (m).
fn dense_normal(nx: usize, ny: usize, dx: f64, dy: f64, es: f64, p: &[f64]) -> Vec<f64> {
    let mut u = vec![0.0; nx * ny];
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nx {
                for l in 0..ny {
                    let ox = (i as f64 - k as f64) * dx;
                    let oy = (j as f64 - l as f64) * dy;
                    u[i * ny + j] += coefficients(ox, oy, dx, dy, es, 80e9, 0.3).zz * p[k * ny + l];
                }
            }
        }
    }
    u
}

#[test]
fn real_normal_product_equals_dense_sum() {
    // r2c normal product: odd (m2 = 15 for ny = 7) and even padded lengths, fields with
    // all-zero rows (skipped in the forward pass) and zero columns
    for &(nx, ny) in &[(4usize, 7usize), (6, 5), (9, 8)] {
        let (dx, dy, es) = (0.4e-3, 0.3e-3, 115e9);
        let mut conv = Convolver::new(nx, ny, dx, dy, es, 80e9, 0.3);
        let n = nx * ny;
        let p: Vec<f64> = (0..n)
            .map(|k| {
                let (i, j) = (k / ny, k % ny);
                if i == 1 || j == ny - 1 {
                    0.0
                } else {
                    ((k * 7919) % 13) as f64 * 1e6 + 1e5
                }
            })
            .collect();
        let mut u = vec![0.0; n];
        conv.normal(&p, &mut u);
        let d = dense_normal(nx, ny, dx, dy, es, &p);
        let umax = d.iter().cloned().fold(0.0, f64::max);
        for e in 0..n {
            assert!(
                (u[e] - d[e]).abs() <= 1e-12 * umax,
                "{nx}x{ny} element {e}: r2c {} vs dense {}",
                u[e],
                d[e]
            );
        }
        // an all-zero field gives exactly zero
        let zero = vec![0.0; n];
        conv.normal(&zero, &mut u);
        assert!(u.iter().all(|&v| v == 0.0));
    }
}

#[test]
fn single_body_coefficients_approach_the_point_load_solutions() {
    // far from a small loaded square the integrals tend to area × the point-load kernels of
    // Boussinesq and Cerruti (Johnson 1985, eqs. 3.22 and 3.86 at the surface)
    let (e, nu) = (210e9, 0.3);
    let g = e / (2.0 * (1.0 + nu));
    let d = 1e-4;
    let area = d * d;
    let (x, y): (f64, f64) = (3e-2, -2e-2);
    let r = (x * x + y * y).sqrt();
    let c = single_body(x, y, d, d, e, nu);
    let pi = std::f64::consts::PI;
    let close = |got: f64, want: f64| (got / want - 1.0).abs() < 1e-4;
    assert!(close(c[2][2], area * (1.0 - nu * nu) / (pi * e * r)));
    let t = area / (2.0 * pi * g);
    assert!(close(
        c[0][0],
        t * ((1.0 - nu) / r + nu * x * x / r.powi(3))
    ));
    assert!(close(
        c[1][1],
        t * ((1.0 - nu) / r + nu * y * y / r.powi(3))
    ));
    assert!(close(c[0][1], t * nu * x * y / r.powi(3)));
    // Boussinesq: the surface moves towards the load, u_x = −(1 − 2ν)(1 + ν) P x / (2π E r²)
    let ux_p = -(1.0 - 2.0 * nu) * (1.0 + nu) * area * x / (2.0 * pi * e * r * r);
    assert!(close(c[0][2], ux_p) && close(c[1][2], ux_p * y / x));
    // Cerruti: u_n = (1 − 2ν) Q x / (4π G r²), and reciprocity c_nx(X) = c_xn(−X)
    assert!(close(c[2][0], -ux_p) && close(c[2][1], -ux_p * y / x));
    let m = single_body(-x, -y, d, d, e, nu);
    assert!((m[0][2] - c[2][0]).abs() < 1e-12 * c[2][0].abs());
    // the pair of two equal bodies is the quasi-identical half-space of `coefficients`
    let pair = coefficients(x, y, d, d, e / (2.0 * (1.0 - nu * nu)), g, nu);
    assert!((2.0 * c[2][2] / pair.zz - 1.0).abs() < 1e-12);
    assert!((2.0 * c[0][0] / pair.xx - 1.0).abs() < 1e-12);
    assert!((2.0 * c[0][1] / pair.xy - 1.0).abs() < 1e-12);
}

/// A kernel that is not Toeplitz across the rail and couples all three components: the
/// half-space pair scaled by a factor depending on the field and source columns, with a
/// normal–tangential coupling of one body's form.
fn strip_test_kernel(o: isize, j: usize, jp: usize) -> [[f64; 3]; 3] {
    let (dx, dy, e, nu) = (0.4e-3, 0.5e-3, 210e9, 0.3);
    let c = single_body(o as f64 * dx, (j as f64 - jp as f64) * dy, dx, dy, e, nu);
    let w = 1.0 + 0.1 * j as f64 + 0.03 * (jp * jp) as f64;
    let mut k = c;
    k.iter_mut().flatten().for_each(|v| *v *= w);
    k
}

#[test]
fn strip_products_equal_dense_sums() {
    // independent check: the dense double sum over the grid, all three components, both the
    // grid's rows and the rows shifted by one
    for (nx, ny) in [(7, 4), (8, 5), (12, 3)] {
        let mut strip = strip::StripConvolver::new(nx, ny, 3, strip_test_kernel);
        let n = nx * ny;
        let f: Vec<Vec<f64>> = (0..3)
            .map(|b| {
                (0..n)
                    .map(|k| (((k + 3 * b) * 7919) % 13) as f64 * 1e6 - 4e6)
                    .collect()
            })
            .collect();
        for shift in 0..2 {
            let mut u = vec![vec![0.0; n]; 3];
            {
                let fr: Vec<&[f64]> = f.iter().map(|v| v.as_slice()).collect();
                let mut ur: Vec<&mut [f64]> = u.iter_mut().map(|v| v.as_mut_slice()).collect();
                strip.product(&fr, &mut ur, shift);
            }
            let mut scale = 0.0_f64;
            let mut worst = 0.0_f64;
            for i in 0..nx {
                for j in 0..ny {
                    for a in 0..3 {
                        let mut d = 0.0;
                        for k in 0..nx {
                            for l in 0..ny {
                                let kb = strip_test_kernel(
                                    i as isize + shift as isize - k as isize,
                                    j,
                                    l,
                                );
                                for (b, fb) in f.iter().enumerate() {
                                    d += kb[a][b] * fb[k * ny + l];
                                }
                            }
                        }
                        scale = scale.max(d.abs());
                        worst = worst.max((u[a][i * ny + j] - d).abs());
                    }
                }
            }
            assert!(
                worst < 1e-12 * scale,
                "{nx}×{ny} shift {shift}: {worst:e} of {scale:e}"
            );
        }
    }
}

#[test]
fn strip_products_of_the_half_space_equal_the_convolver() {
    let (nx, ny, dx, dy) = (16, 12, 0.45e-3, 0.5e-3);
    let (es, g, nu) = (115e9, 80e9, 0.3);
    let mut conv = Convolver::new(nx, ny, dx, dy, es, g, nu);
    let kernel = |comps| strip::half_space_kernel((dx, dy), (es, g, nu), comps);
    let mut normal = strip::StripConvolver::new(nx, ny, 1, kernel(1));
    let mut tangential = strip::StripConvolver::new(nx, ny, 2, kernel(2));
    let n = nx * ny;
    let p: Vec<f64> = (0..n).map(|k| ((k * 31) % 17) as f64 * 1e6).collect();
    let q: Vec<f64> = (0..n).map(|k| ((k * 13) % 7) as f64 * 1e6 - 3e6).collect();
    let (mut u, mut us) = (vec![0.0; n], vec![0.0; n]);
    conv.normal(&p, &mut u);
    normal.product(&[&p], &mut [&mut us], 0);
    let close = |a: &[f64], b: &[f64]| {
        let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12 * scale)
    };
    assert!(close(&u, &us));
    for shift in 0..2 {
        let (mut ux, mut uy) = (vec![0.0; n], vec![0.0; n]);
        let (mut sx, mut sy) = (vec![0.0; n], vec![0.0; n]);
        conv.tangential(&p, &q, &mut ux, &mut uy, shift);
        tangential.product(&[&p, &q], &mut [&mut sx, &mut sy], shift);
        assert!(close(&ux, &sx) && close(&uy, &sy), "shift {shift}");
    }
}
