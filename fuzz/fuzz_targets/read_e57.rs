//! Any bytes, made into E57 pages with valid checksums (`e57_pages.rs`), must give a cloud or an
//! error: never a panic, never a huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let bytes = e57_pages(data);
    if let Ok(cloud) = arps::io::read_point_cloud(&bytes, "a.e57") {
        assert!(reads_back(&cloud));
    }
});

include!("../same_points.rs");
include!("../e57_pages.rs");
