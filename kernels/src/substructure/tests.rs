use super::*;

/// The dense interface Cholesky on `Par::rayon(2)` gives the same bits in a pool of
/// one thread as in a pool of two (faer splits the work by the task count it is
/// given, not by the threads that run it): what makes the backend thread-independent.
#[test]
fn interface_cholesky_is_bit_identical_for_1_and_2_threads() {
    let n = 1500;
    // SPD: diagonally dominant with a deterministic pseudo-random symmetric part
    let mut a = Mat::<f64>::zeros(n, n);
    let mut state = 12345u64;
    for j in 0..n {
        for i in j..n {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            let v = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            a[(i, j)] = if i == j { n as f64 } else { v };
        }
    }
    let run = || {
        let mut s = a.clone();
        let par = Par::rayon(2);
        let req = cholesky_in_place_scratch::<f64>(n, par, Default::default());
        let mut mem = MemBuffer::new(req);
        let stack = MemStack::new(&mut mem);
        cholesky_in_place(
            s.as_mut(),
            Default::default(),
            par,
            stack,
            Default::default(),
        )
        .unwrap();
        let lower = (0..n).flat_map(|j| (j..n).map(move |i| (i, j)));
        lower.map(|(i, j)| s[(i, j)].to_bits()).collect::<Vec<_>>()
    };
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    assert!(pool(1).install(run) == pool(2).install(run));
}
