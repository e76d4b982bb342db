//! Mitsuba grid volumes (`.vol`) from arbitrary bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = neumann::load::volume::parse_grid_volume(data);
});
