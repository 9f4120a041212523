//! Defect 3 of issue 14: a compressed PCD whose header promised 88 times its size made the decoder
//! reserve that much before checking the data (a 16 MB file left 1.4 GB of wasm memory behind).
//! This binary counts its allocations, so it holds this one test only.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
        PEAK.fetch_max(live, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn compressed_pcd_promising_more_than_it_holds_costs_no_more_than_it_holds() {
    // 600,000 compressed bytes declaring 88 x as much (52.8 MB = 4.4M xyz points); the payload
    // is 1-byte literal runs, so it really decompresses to 300,000 bytes
    let comp = 600_000usize;
    let uncomp = comp * 88;
    let n = uncomp / 12;
    let mut file = format!(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary_compressed\n"
    )
    .into_bytes();
    file.extend_from_slice(&(comp as u32).to_le_bytes());
    file.extend_from_slice(&(uncomp as u32).to_le_bytes());
    file.extend(std::iter::repeat_n([0u8, 7u8], comp / 2).flatten());
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    let e = arps::io::read_point_cloud(&file, "promise.pcd").unwrap_err().to_string();
    assert!(e.contains("decompresses to 300000 bytes"), "{e}");
    let peak = PEAK.load(Ordering::SeqCst) - before;
    assert!(peak < 8 << 20, "decoding a {} byte file peaked at {peak} bytes", file.len());
}
