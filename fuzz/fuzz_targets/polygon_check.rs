//! Any list of vertices (pairs of f64 from the input bytes, NaN and infinities
//! included): the polygon check returns Ok or a defect, never panics.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let v: Vec<[f64; 2]> = data
        .chunks_exact(16)
        .map(|c| {
            let x = f64::from_le_bytes(c[..8].try_into().unwrap());
            let y = f64::from_le_bytes(c[8..].try_into().unwrap());
            [x, y]
        })
        .collect();
    let _ = dfem::geometry::polygon::check(&v, 1e-9);
    let _ = dfem::geometry::polygon::signed_area(&v);
});
