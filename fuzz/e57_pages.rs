// Shared by the `read_e57` fuzz target and `tests/io_fuzz_regressions.rs`, through `include!`:
// mutated bytes made into E57 pages that pass their checksums, so that the fuzzer reaches what
// the pages hold (the header, the XML, the binary sections) instead of stopping at a checksum.

/// E57's page: 1,020 bytes of data and their CRC-32C, big-endian.
const E57_PAGE: usize = 1024;

/// CRC-32C (Castagnoli), bit by bit (inputs are small).
fn crc32c(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0x82F6_3B78 } else { crc >> 1 };
        }
    }
    !crc
}

/// `data` cut to whole pages, each page's checksum rewritten to match its data.
fn e57_pages(data: &[u8]) -> Vec<u8> {
    let mut b = data[..data.len() / E57_PAGE * E57_PAGE].to_vec();
    for page in b.chunks_exact_mut(E57_PAGE) {
        let crc = crc32c(&page[..E57_PAGE - 4]);
        page[E57_PAGE - 4..].copy_from_slice(&crc.to_be_bytes());
    }
    b
}
