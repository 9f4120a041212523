//! Headers that lie about their counts must not make the readers allocate for them: every
//! case below is a small file claiming billions of items, and the largest single allocation
//! made while reading it must stay small. (One test in this binary, so nothing else allocates
//! concurrently.)

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Tracking;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

fn pad(mut b: Vec<u8>, filler: &[u8]) -> Vec<u8> {
    while b.len() < 1024 {
        b.extend_from_slice(filler);
    }
    b
}

#[test]
fn lying_headers_do_not_allocate() {
    let pcd = |data: &str, body: &[u8]| {
        let mut b = format!("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4000000000\nHEIGHT 1\nPOINTS 4000000000\nDATA {data}\n").into_bytes();
        b.extend_from_slice(body);
        pad(b, b"0 0 0\n")
    };
    let mut compressed_sizes = Vec::new();
    compressed_sizes.extend_from_slice(&1000u32.to_le_bytes());
    compressed_sizes.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    let mut stl = vec![b' '; 80];
    stl.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("a.ply", pad(b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(), &[0])),
        ("a.ply", pad(b"ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(), b"0 0 0\n")),
        (
            "a.ply",
            pad(
                b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty list uchar float n\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(),
                &[0],
            ),
        ),
        ("a.pcd", pcd("ascii", b"")),
        ("a.pcd", pcd("binary", b"")),
        ("a.pcd", pcd("binary_compressed", &compressed_sizes)),
        ("a.off", pad(b"OFF\n4000000000 4000000000 0\n".to_vec(), b"0 0 0\n")),
        ("a.stl", pad(stl, &[0])),
    ];
    // The tracker sees allocations.
    LARGEST.store(0, Ordering::Relaxed);
    let v: Vec<u8> = Vec::with_capacity(1 << 20);
    assert!(LARGEST.load(Ordering::Relaxed) >= 1 << 20);
    drop(v);
    for (name, bytes) in &cases {
        LARGEST.store(0, Ordering::Relaxed);
        let r = arps::io::read_point_cloud(bytes, name);
        let largest = LARGEST.load(Ordering::Relaxed);
        let msg = r.as_ref().err().map(|e| e.to_string()).unwrap_or_default();
        assert!(r.is_err(), "{name}: a {}-byte file claiming 4e9 items read fine", bytes.len());
        assert!(largest < 64 * 1024, "{name}: allocated {largest} bytes at once ({msg})");
        LARGEST.store(0, Ordering::Relaxed);
        assert!(arps::io::read_mesh(bytes, name).is_err() || name.ends_with(".pcd"));
        assert!(LARGEST.load(Ordering::Relaxed) < 64 * 1024, "{name}: read_mesh allocated too much");
    }
}
