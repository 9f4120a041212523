//! The same cloud written in every PLY and PCD variant (small writers below) reads back
//! bit-identical, NaN included; and `write_ply_binary` round-trips.

use arps::io::{read_mesh, read_point_cloud, write_ply_binary};
use arps::PointCloud;
use rand::Rng;

/// 500 points on a 25 x 20 grid, with a few NaN "no return" points and extreme values.
fn cloud() -> PointCloud {
    let mut rng = arps::sampling::rng(7);
    let mut pts: Vec<[f32; 3]> = (0..500).map(|_| [0, 1, 2].map(|_| rng.random_range(-100.0f32..100.0))).collect();
    pts[3] = [f32::NAN; 3];
    pts[77] = [f32::NAN; 3];
    pts[10] = [1e-30, -0.0, 3.4e38];
    pts[11] = [f32::MIN_POSITIVE, 1.0 / 3.0, -7.0];
    PointCloud::new(pts)
}

fn bits(c: &PointCloud) -> Vec<[u32; 3]> {
    c.points.iter().map(|p| p.map(f32::to_bits)).collect()
}

// ---------------------------------------------------------------- PLY

#[derive(Clone, Copy, PartialEq)]
enum Ply {
    Ascii,
    Le,
    Be,
}

/// Vertex properties: `uchar red, double x, float nx, list uchar int tags, float y, ushort id,
/// float z` (x as double on purpose), a `face` element before the vertices and an `edge`
/// element after them.
fn write_ply(c: &PointCloud, enc: Ply) -> Vec<u8> {
    let fmt = match enc {
        Ply::Ascii => "ascii",
        Ply::Le => "binary_little_endian",
        Ply::Be => "binary_big_endian",
    };
    let n = c.len();
    let mut out = format!(
        "ply\r\nformat {fmt} 1.0\r\ncomment made by a test\r\nobj_info anything\r\nelement face 2\r\nproperty list uchar uint vertex_indices\r\nproperty float quality\r\n\
         element vertex {n}\r\nproperty uchar red\r\nproperty double x\r\nproperty float nx\r\nproperty list uchar int tags\r\nproperty float y\r\nproperty ushort id\r\nproperty float z\r\n\
         element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
    )
    .into_bytes();
    let faces: [&[u32]; 2] = [&[0, 1, 2], &[2, 3, 4, 5]];
    match enc {
        Ply::Ascii => {
            let mut s = String::new();
            for f in faces {
                s += &format!("{} {} 0.5\n", f.len(), f.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" "));
            }
            for (i, p) in c.points.iter().enumerate() {
                let tags = (0..i % 3).map(|k| format!(" {}", k as i32 - 1)).collect::<String>();
                s += &format!("{} {} 0.25 {}{tags} {} {} {}\n", i % 256, p[0] as f64, i % 3, p[1], i % 65536, p[2]);
            }
            s += "0 1\n";
            out.extend_from_slice(s.as_bytes());
        }
        Ply::Le | Ply::Be => {
            let be = enc == Ply::Be;
            macro_rules! put {
                ($v:expr) => {
                    if be {
                        out.extend_from_slice(&$v.to_be_bytes())
                    } else {
                        out.extend_from_slice(&$v.to_le_bytes())
                    }
                };
            }
            for f in faces {
                out.push(f.len() as u8);
                for &i in f {
                    put!(i);
                }
                put!(0.5f32);
            }
            for (i, p) in c.points.iter().enumerate() {
                out.push((i % 256) as u8);
                put!(p[0] as f64);
                put!(0.25f32);
                out.push((i % 3) as u8);
                for k in 0..i % 3 {
                    put!(k as i32 - 1);
                }
                put!(p[1]);
                put!((i % 65536) as u16);
                put!(p[2]);
            }
            put!(0i32);
            put!(1i32);
        }
    }
    out
}

#[test]
fn ply_variants_read_back_identical() {
    let c = cloud();
    for enc in [Ply::Ascii, Ply::Le, Ply::Be] {
        let bytes = write_ply(&c, enc);
        let back = read_point_cloud(&bytes, "cloud.ply").unwrap();
        assert_eq!(bits(&back), bits(&c));
        let mesh = read_mesh(&bytes, "cloud.ply").unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [2, 3, 4], [2, 4, 5]]);
        assert_eq!(bits(&PointCloud::new(mesh.vertices)), bits(&c));
    }
}

#[test]
fn write_ply_binary_round_trips() {
    let c = cloud();
    let bytes = write_ply_binary(&c);
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    assert_eq!(bits(&read_point_cloud(&bytes, "out.ply").unwrap()), bits(&c));
    assert_eq!(bits(&read_point_cloud(&bytes, "no-extension").unwrap()), bits(&c));
    let empty = write_ply_binary(&PointCloud::default());
    // a file with no points is an error, not an empty cloud (issue 14)
    let e = read_point_cloud(&empty, "e.ply").unwrap_err().to_string();
    assert!(e.contains("holds no points"), "{e}");
}

// ---------------------------------------------------------------- PCD

#[derive(Clone, Copy, PartialEq)]
enum Pcd {
    Ascii,
    Binary,
    Compressed,
}

/// Fields: `rgb` F4, `x` F4, `y` F8, `_` U1 x3 (padding), `z` F4, `normal_x` F4, `intensity` U2;
/// organised 25 x 20.
fn write_pcd(c: &PointCloud, data: Pcd) -> Vec<u8> {
    let kind = match data {
        Pcd::Ascii => "ascii",
        Pcd::Binary => "binary",
        Pcd::Compressed => "binary_compressed",
    };
    let mut out = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS rgb x y _ z normal_x intensity\nSIZE 4 4 8 1 4 4 2\nTYPE F F F U F F U\nCOUNT 1 1 1 3 1 1 1\n\
         WIDTH 25\nHEIGHT 20\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {kind}\n",
        c.len()
    )
    .into_bytes();
    // Per-field values of point i, as little-endian bytes.
    let field = |f: usize, i: usize| -> Vec<u8> {
        let p = c.points[i];
        match f {
            0 => 4.2e6f32.to_le_bytes().to_vec(),
            1 => p[0].to_le_bytes().to_vec(),
            2 => (p[1] as f64).to_le_bytes().to_vec(),
            3 => vec![0, 0, 0],
            4 => p[2].to_le_bytes().to_vec(),
            5 => (-0.5f32).to_le_bytes().to_vec(),
            _ => ((i % 65536) as u16).to_le_bytes().to_vec(),
        }
    };
    match data {
        Pcd::Ascii => {
            for (i, p) in c.points.iter().enumerate() {
                out.extend_from_slice(format!("4.2e6 {} {} 0 0 0 {} -0.5 {}\n", p[0], p[1] as f64, p[2], i).as_bytes());
            }
        }
        Pcd::Binary => {
            for i in 0..c.len() {
                for f in 0..7 {
                    out.extend_from_slice(&field(f, i));
                }
            }
        }
        Pcd::Compressed => {
            let mut raw = Vec::new();
            for f in 0..7 {
                for i in 0..c.len() {
                    raw.extend_from_slice(&field(f, i));
                }
            }
            let packed = lzf_compress(&raw);
            out.extend_from_slice(&(packed.len() as u32).to_le_bytes());
            out.extend_from_slice(&(raw.len() as u32).to_le_bytes());
            out.extend_from_slice(&packed);
        }
    }
    out
}

/// A greedy LZF compressor (liblzf's format), for writing binary_compressed PCD.
fn lzf_compress(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut lit: Vec<u8> = Vec::new();
    let mut table = std::collections::HashMap::new();
    let flush = |lit: &mut Vec<u8>, out: &mut Vec<u8>| {
        for chunk in lit.chunks(32) {
            out.push(chunk.len() as u8 - 1);
            out.extend_from_slice(chunk);
        }
        lit.clear();
    };
    let mut i = 0;
    while i < data.len() {
        if i + 2 < data.len() {
            let key = [data[i], data[i + 1], data[i + 2]];
            if let Some(r) = table.insert(key, i) {
                let off = i - r - 1;
                if off < 8192 {
                    let max = 264.min(data.len() - i);
                    let mut len = 3;
                    while len < max && data[r + len] == data[i + len] {
                        len += 1;
                    }
                    flush(&mut lit, &mut out);
                    let l = len - 2;
                    if l < 7 {
                        out.push(((l << 5) | (off >> 8)) as u8);
                    } else {
                        out.push(((7 << 5) | (off >> 8)) as u8);
                        out.push((l - 7) as u8);
                    }
                    out.push((off & 0xff) as u8);
                    i += len;
                    continue;
                }
            }
        }
        lit.push(data[i]);
        i += 1;
    }
    flush(&mut lit, &mut out);
    out
}

#[test]
fn pcd_variants_read_back_identical() {
    let c = cloud();
    for data in [Pcd::Ascii, Pcd::Binary, Pcd::Compressed] {
        let bytes = write_pcd(&c, data);
        let back = read_point_cloud(&bytes, "cloud.pcd").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(bits(&back), bits(&c));
        assert_eq!(bits(&read_point_cloud(&bytes, "sniffed").unwrap()), bits(&c));
    }
}

#[test]
fn pcd_compressed_actually_compresses_repetitive_fields() {
    let bytes = write_pcd(&cloud(), Pcd::Compressed);
    assert!(bytes.len() < write_pcd(&cloud(), Pcd::Binary).len());
}

// ---------------------------------------------------------------- text

#[test]
fn text_variants_read_back_identical() {
    let c = cloud();
    let rows = |sep: &str| -> String {
        c.points.iter().map(|p| format!("{}{sep}{}{sep}{}{sep}7{sep}8\n", p[0], p[1], p[2])).collect()
    };
    let variants = [
        ("c.xyz", rows(" ")),
        ("c.txt", format!("# exported\n{}", rows("\t"))),
        ("c.pts", format!("{}\n{}", c.len(), rows(" "))),
        ("c.csv", format!("x,y,z,i,j\n{}", rows(","))),
        ("c.csv", format!("X;Y;Z;A;B\r\n{}", rows(";").replace('\n', "\r\n"))),
        ("c.csv", format!("x, y, z\n\n{}", rows(", "))),
    ];
    for (name, text) in variants {
        let back = read_point_cloud(text.as_bytes(), name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(bits(&back), bits(&c), "{name}");
    }
}
