//! NanoVDB files (`.nvdb`) from arbitrary bytes: the file's segments and codecs, the grid's tree
//! checked on reading, and lookups anywhere through whatever grid it gives.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = neumann::load::nanovdb::grid_names(data);
    if let Ok(Some(g)) = neumann::load::nanovdb::parse_nanovdb(data, "density") {
        let [lo, hi] = g.index_bbox();
        let _ = g.max_in(lo, hi);
        for k in 0..64 {
            let x = [(k % 4) as f32 * 9.7 - 20.0, (k / 4 % 4) as f32 * 7.3 - 12.0, (k / 16) as f32 * 11.1 - 17.0];
            let v = g.sample(x);
            assert!(v.is_finite());
            let _ = g.value([x[0] as i32, x[1] as i32, x[2] as i32]);
            let _ = g.world_to_index(g.index_to_world(x));
        }
    }
});
