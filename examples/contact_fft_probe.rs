use corrugation::contact::influence::Convolver;
use std::time::Instant;
fn main() {
    for &n in &[25usize, 27, 32, 40, 51, 52, 54, 64] {
        let mut c = Convolver::new(n, n, 1e-4, 1e-4, 115e9, 80e9, 0.3);
        let p: Vec<f64> = (0..n * n).map(|k| (k % 7) as f64).collect();
        let mut u = vec![0.0; n * n];
        let mut v = vec![0.0; n * n];
        let reps = 2000;
        let t = Instant::now();
        for _ in 0..reps {
            c.normal(&p, &mut u);
        }
        let tn = t.elapsed().as_secs_f64() / reps as f64;
        let t = Instant::now();
        for _ in 0..reps {
            c.tangential(&p, &p, &mut u, &mut v, 0);
        }
        let tt = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "n {n} {:?}: normal {:.1} us, tangential {:.1} us",
            c.fft_dims(),
            tn * 1e6,
            tt * 1e6
        );
    }
}
