//! Malformed input gives an `Err` whose message says what and where; never a panic.

use arps::io::{detect_format, read_mesh, read_point_cloud};

/// The error message of reading `bytes` as a point cloud named `name`.
fn cloud_err(bytes: &[u8], name: &str) -> String {
    match read_point_cloud(bytes, name) {
        Ok(c) => panic!("{name}: expected an error, read {} points", c.len()),
        Err(e) => e.to_string(),
    }
}

fn mesh_err(bytes: &[u8], name: &str) -> String {
    match read_mesh(bytes, name) {
        Ok(m) => panic!("{name}: expected an error, read {} triangles", m.triangles.len()),
        Err(e) => e.to_string(),
    }
}

#[track_caller]
fn has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in: {msg}");
    }
}

const PLY_XYZ: &str =
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";

fn ply_binary(vertex_count: u64, faces: u64, body: &[u8]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertex_count}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    b.extend_from_slice(body);
    b
}

fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

#[test]
fn ply_header_errors() {
    has(&cloud_err(b"plx\nformat ascii 1.0\n", "a.ply"), &["PLY", "'ply' magic"]);
    has(&cloud_err(b"ply\nformat ascii 1.0\nelement vertex 1\n", "a.ply"), &["no 'end_header'"]);
    has(&cloud_err(b"ply\nformat utf16 1.0\nend_header\n", "a.ply"), &["line 2", "unknown format 'utf16'"]);
    has(
        &cloud_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n", "a.ply"),
        &["line 4", "unknown property type 'float128'"],
    );
    has(
        &cloud_err(b"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "a.ply"),
        &["line 3", "before any 'element'"],
    );
    has(&cloud_err(b"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "a.ply"), &["line 3", "count '-1'"]);
    has(
        &cloud_err(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n", "a.ply"),
        &["line 4", "list count type"],
    );
    has(
        &cloud_err(
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n",
            "a.ply",
        ),
        &["no 'z' property"],
    );
    has(
        &cloud_err(b"ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n", "a.ply"),
        &["no 'vertex' element"],
    );
    has(&cloud_err(b"ply\nelement vertex 0\nend_header\n", "a.ply"), &["no 'format' line"]);
    has(
        &cloud_err(b"ply\nformat ascii 1.0\nwhatever 3\nend_header\n", "a.ply"),
        &["line 3", "unknown header keyword 'whatever'"],
    );
    // Non-UTF-8 in a header line (comments may hold any bytes).
    let mut b = b"ply\nformat ascii 1.0\ncomment caf\xe9\nelement vert\xffex 1\nend_header\n".to_vec();
    has(&cloud_err(&b, "a.ply"), &["header line 4", "UTF-8"]);
    b.truncate(0);
}

#[test]
fn ply_body_errors() {
    // Ascii: a bad number, a missing value, too few lines.
    has(&cloud_err(format!("{PLY_XYZ}1 2 3\n1 zwei 3\n").as_bytes(), "a.ply"), &["line 9", "'y'", "'zwei'"]);
    has(&cloud_err(format!("{PLY_XYZ}1 2 3\n1 2\n").as_bytes(), "a.ply"), &["line 9", "missing a value", "'z'"]);
    has(&cloud_err(format!("{PLY_XYZ}1 2 3\n").as_bytes(), "a.ply"), &["ends after 1 of the 2 'vertex' lines"]);
    // A header claiming 7e6 vertices in a tiny ascii file (4e9 is over the budget: too large).
    has(
        &cloud_err(PLY_XYZ.replace("vertex 2", "vertex 4000000000").as_bytes(), "a.ply"),
        &["too large", "4000000000 points"],
    );
    let lying = PLY_XYZ.replace("vertex 2", "vertex 7000000") + "1 2 3\n";
    has(&cloud_err(lying.as_bytes(), "a.ply"), &["ends after 1 of the 7000000"]);
    // Binary: truncated vertex data.
    has(
        &cloud_err(&ply_binary(2, 0, &floats(&[1.0, 2.0, 3.0, 4.0])), "a.ply"),
        &["element 'vertex'", "declares 2 instances", "byte offset"],
    );
    // A header claiming 7e6 vertices in a 1 KB binary file.
    has(
        &cloud_err(&ply_binary(7_000_000, 0, &[0u8; 1024]), "a.ply"),
        &["declares 7000000 instances", "only 1024 bytes"],
    );
    // Faces: truncated list, out-of-range index, negative index.
    let verts = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let mut body = verts.clone();
    body.push(3);
    body.extend_from_slice(&[0u8; 5]);
    has(
        &mesh_err(&ply_binary(3, 1, &body), "a.ply"),
        &["truncated", "element 'face' instance 0", "'vertex_indices'", "byte offset"],
    );
    let mut body = verts.clone();
    body.push(3);
    for i in [0i32, 1, 3] {
        body.extend_from_slice(&i.to_le_bytes());
    }
    has(&mesh_err(&ply_binary(3, 1, &body), "a.ply"), &["face 0", "vertex index 3 is out of range (3 vertices)"]);
    let mut body = verts;
    body.push(3);
    for i in [0i32, -1, 2] {
        body.extend_from_slice(&i.to_le_bytes());
    }
    has(&mesh_err(&ply_binary(3, 1, &body), "a.ply"), &["vertex index -1 is out of range"]);
    // Ascii faces.
    let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    has(&mesh_err(format!("{ascii}3 0 1 7\n").as_bytes(), "a.ply"), &["line 13", "vertex index 7 is out of range"]);
    has(&mesh_err(format!("{ascii}4 0 1 2\n").as_bytes(), "a.ply"), &["line 13", "declares 4 items but only 3 follow"]);
    has(&mesh_err(format!("{ascii}-3 0 1 2\n").as_bytes(), "a.ply"), &["line 13", "length of list"]);
    has(
        &mesh_err(ascii.replace("element face 1\nproperty list uchar int vertex_indices\n", "").as_bytes(), "a.ply"),
        &["no 'face' element"],
    );
    // Negative list length in binary (signed count type).
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty list char float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    b.push(0xff);
    has(&cloud_err(&b, "a.ply"), &["vertex property 'x' is a list"]);
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty list char float n\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    b.extend_from_slice(&[0xff; 13]);
    has(&cloud_err(&b, "a.ply"), &["negative length -1"]);
}

const PCD_HEAD: &str =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";

#[test]
fn pcd_header_errors() {
    has(&cloud_err(PCD_HEAD.as_bytes(), "a.pcd"), &["PCD", "no DATA line"]);
    has(
        &cloud_err(format!("{}DATA ascii\n", PCD_HEAD.replace("SIZE 4 4 4", "SIZE 4 4")).as_bytes(), "a.pcd"),
        &["line 4", "SIZE has 2 entries but FIELDS (line 3) names 3"],
    );
    has(&cloud_err(PCD_HEAD.replace("TYPE F F F", "TYPE F F Q").as_bytes(), "a.pcd"), &["line 5", "unknown TYPE 'Q'"]);
    has(
        &cloud_err(format!("{}DATA ascii\n", PCD_HEAD.replace("SIZE 4 4 4", "SIZE 4 4 3")).as_bytes(), "a.pcd"),
        &["field 'z'", "TYPE F with SIZE 3"],
    );
    has(
        &cloud_err(format!("{}DATA ascii\n", PCD_HEAD.replace("POINTS 2", "POINTS 3")).as_bytes(), "a.pcd"),
        &["WIDTH 2 x HEIGHT 1 = 2, but POINTS is 3"],
    );
    has(
        &cloud_err(format!("{}DATA ascii\n", PCD_HEAD.replace("FIELDS x y z", "FIELDS x y w")).as_bytes(), "a.pcd"),
        &["no 'z' field"],
    );
    has(&cloud_err(format!("{PCD_HEAD}DATA zip\n").as_bytes(), "a.pcd"), &["line 10", "unknown DATA 'zip'"]);
    has(
        &cloud_err(format!("{PCD_HEAD}COLOR red\nDATA ascii\n").as_bytes(), "a.pcd"),
        &["line 10", "unknown header keyword 'COLOR'"],
    );
    has(&cloud_err(b"# .PCD v0.7\nVERSION 0.7\nFIELDS x \xff\n", "a.pcd"), &["header line 3", "UTF-8"]);
    has(
        &cloud_err(
            format!("{}DATA ascii\n", PCD_HEAD.replace("WIDTH 2\nHEIGHT 1", "WIDTH 4294967296\nHEIGHT 4294967296"))
                .as_bytes(),
            "a.pcd",
        ),
        &["overflows"],
    );
}

#[test]
fn pcd_body_errors() {
    has(
        &cloud_err(format!("{PCD_HEAD}DATA ascii\n1 2 3\n1 2\n").as_bytes(), "a.pcd"),
        &["line 12", "expected 3 values per point, found 2"],
    );
    has(&cloud_err(format!("{PCD_HEAD}DATA ascii\n1 2 3\n1 2 x\n").as_bytes(), "a.pcd"), &["line 12", "'z'", "'x'"]);
    has(&cloud_err(format!("{PCD_HEAD}DATA ascii\n1 2 3\n").as_bytes(), "a.pcd"), &["ends after 1 of the 2 points"]);
    // Binary: truncated, and a lying 4e9-point header.
    let mut b = format!("{PCD_HEAD}DATA binary\n").into_bytes();
    b.extend_from_slice(&floats(&[1.0, 2.0, 3.0, 4.0]));
    has(&cloud_err(&b, "a.pcd"), &["truncated binary data", "2 points of 12 bytes need 24 bytes", "byte offset"]);
    let lying =
        format!("{}DATA binary\n", PCD_HEAD.replace("WIDTH 2", "WIDTH 7000000").replace("POINTS 2", "POINTS 7000000"));
    let mut b = lying.into_bytes();
    b.extend_from_slice(&[0u8; 1024]);
    has(&cloud_err(&b, "a.pcd"), &["truncated binary data", "7000000 points"]);
    // Compressed: missing sizes, lying sizes, corrupt stream.
    let head = format!("{PCD_HEAD}DATA binary_compressed\n").into_bytes();
    let with = |comp: u32, uncomp: u32, payload: &[u8]| {
        let mut b = head.clone();
        b.extend_from_slice(&comp.to_le_bytes());
        b.extend_from_slice(&uncomp.to_le_bytes());
        b.extend_from_slice(payload);
        b
    };
    has(&cloud_err(&head, "a.pcd"), &["8-byte size header is missing"]);
    has(&cloud_err(&with(100, 24, &[0; 10]), "a.pcd"), &["declares 100 compressed bytes", "only 10 remain"]);
    has(&cloud_err(&with(2, 25, &[0; 2]), "a.pcd"), &["declares 25 uncompressed bytes", "need 24"]);
    let big = format!(
        "{}DATA binary_compressed\n",
        PCD_HEAD.replace("WIDTH 2", "WIDTH 3000000").replace("POINTS 2", "POINTS 3000000")
    );
    let mut b = big.into_bytes();
    b.extend_from_slice(&4u32.to_le_bytes());
    b.extend_from_slice(&36_000_000u32.to_le_bytes());
    b.extend_from_slice(&[0; 4]);
    has(&cloud_err(&b, "a.pcd"), &["more than LZF can produce"]);
    // A back-reference before the start of the output.
    has(&cloud_err(&with(2, 24, &[0x20, 0x05]), "a.pcd"), &["compressed byte 0", "before the start"]);
    // A literal run cut off.
    has(&cloud_err(&with(3, 24, &[23, 1, 2]), "a.pcd"), &["literal run", "past the end"]);
    // Decompresses to fewer bytes than declared.
    has(&cloud_err(&with(3, 24, &[1, 1, 2]), "a.pcd"), &["decompresses to 2 bytes", "declares 24"]);
}

#[test]
fn text_errors() {
    has(&cloud_err(b"1 2 3\n4 5 6\n7 8\n", "a.xyz"), &["XYZ", "line 3", "at least 3 numbers"]);
    has(
        &cloud_err(b"x y z\n1 2 3\n4 5 6\n7 8\n", "a.xyz"),
        &["line 4", "x, y, z in columns [1, 2, 3] (named in the header)"],
    );
    has(&cloud_err(b"1,2,3\n4,five,6\n", "a.csv"), &["line 2", "'five'"]);
    has(&cloud_err(b"x y z\n# nothing\n", "a.xyz"), &["no line with three numbers"]);
    has(&cloud_err(b"", "a.txt"), &["XYZ parse error: the file is empty (0 bytes)"]);
    has(&cloud_err(b"", "a.ply"), &["PLY parse error: the file is empty (0 bytes)"]);
    has(&cloud_err(b"1 2 3\n4 5 \xff\n", "a.xyz"), &["line 2", "UTF-8"]);
}

#[test]
fn obj_errors() {
    let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    has(
        &mesh_err(format!("{v}f 1 2 4\n").as_bytes(), "a.obj"),
        &["OBJ", "line 4", "vertex index 3 is out of range (3 vertices)"],
    );
    has(&mesh_err(format!("{v}f 0 1 2\n").as_bytes(), "a.obj"), &["line 4", "index 0 is invalid"]);
    has(&mesh_err(format!("{v}f -1 -2 -4\n").as_bytes(), "a.obj"), &["line 4", "relative face index -4"]);
    has(&mesh_err(format!("{v}f x/1 2 3\n").as_bytes(), "a.obj"), &["line 4", "face vertex index 'x'"]);
    has(&cloud_err(b"v 1 2\n", "a.obj"), &["line 1", "vertex has 2 coordinates"]);
    has(&cloud_err(b"v 1 2 drei\n", "a.obj"), &["line 1", "'drei'"]);
}

#[test]
fn off_errors() {
    has(&mesh_err(b"OFX\n3 1 0\n", "a.off"), &["OFF", "line 1", "expected an OFF header"]);
    has(
        &mesh_err(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "a.off"),
        &["line 6", "vertex index 3 is out of range"],
    );
    has(&mesh_err(b"OFF\n7000000 1 0\n0 0 0\n", "a.off"), &["ends after 1 of the 7000000 vertices"]);
    has(&mesh_err(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", "a.off"), &["ends after 0 of the 1 faces"]);
    has(&mesh_err(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n", "a.off"), &["ends inside face 0"]);
    has(&mesh_err(b"4OFF\n3 1 0\n", "a.off"), &["not supported"]);
    has(&mesh_err(b"OFF BINARY\n", "a.off"), &["binary OFF is not supported"]);
    has(&mesh_err(b"OFF\n3 x 0\n", "a.off"), &["line 2", "face count 'x'"]);
    has(&mesh_err(b"OFF\n1 0 0\n0 0 zero\n", "a.off"), &["line 3", "'zero'"]);
}

#[test]
fn stl_errors() {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 1000]);
    has(&mesh_err(&b, "a.stl"), &["STL", "truncated binary STL", "4000000000 facets"]);
    has(&mesh_err(&[0u8; 50], "a.stl"), &["84-byte header"]);
    has(&mesh_err(b"solid x\nvertex 1 2 3\n", "a.stl"), &["line 2", "outside an 'outer loop'"]);
    has(
        &mesh_err(
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n",
            "a.stl",
        ),
        &["line 6", "has 2 vertices, expected 3"],
    );
    has(
        &mesh_err(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "a.stl"),
        &["ends inside the facet loop opened at line 3"],
    );
    has(&mesh_err(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nope\n", "a.stl"), &["line 4", "'nope'"]);
    has(&mesh_err(b"solid x\nendsolid x\n", "a.stl"), &["no facets"]);
    // A binary file whose header starts with "solid", truncated: the hint names the size rule.
    let mut b = b"solid binary header".to_vec();
    b.resize(80, 0);
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 60]);
    has(&mesh_err(&b, "a.stl"), &["if this is a binary STL", "declares 2 facets", "184 bytes", "144 bytes"]);
}

#[test]
fn detection_and_kind_errors() {
    let e = detect_format(b"\x00\x01\x02 binary junk", "upload.bin").unwrap_err().to_string();
    has(&e, &["cannot tell the format of 'upload.bin'"]);
    has(&cloud_err(b"hello world\n", "README"), &["cannot tell the format"]);
    // No file name at all (e.g. `parsePointCloud(bytes)` from JavaScript): the message says so.
    let e = detect_format(b"hello world\n", "").unwrap_err().to_string();
    has(&e, &["no file name was given", "scan.ply"]);
    has(&mesh_err(b"1 2 3\n", "a.xyz"), &["XYZ", "points only"]);
    has(&mesh_err(format!("{PCD_HEAD}DATA ascii\n1 2 3\n4 5 6\n").as_bytes(), "a.pcd"), &["PCD", "points only"]);
    // A signature wins over the extension: a PCD named .ply is read, and fails, as PCD; without
    // one the extension rules: a PCD header without its `# .PCD` line, named .ply, is no PLY.
    has(
        &cloud_err(format!("{PCD_HEAD}DATA ascii\n").as_bytes(), "a.ply"),
        &["PCD", "the file ends after 0 of the 2 points"],
    );
    let unsigned = PCD_HEAD.lines().filter(|l| !l.starts_with('#')).collect::<Vec<_>>().join("\n");
    has(&cloud_err(format!("{unsigned}\nDATA ascii\n").as_bytes(), "a.ply"), &["PLY", "'ply' magic"]);
}
