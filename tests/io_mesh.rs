//! Mesh reading (polygons, index forms) and area-weighted surface sampling.

use arps::io::{read_mesh, Mesh};

/// A unit cube centred at the origin, as OBJ with quads, mixed index forms and negative indices.
const CUBE_OBJ: &str = "# cube\nmtllib cube.mtl\no cube\n\
v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
vt 0 0\nvn 0 0 1\ng faces\nusemtl m\ns off\n\
f 1 4 3 2\nf 5/1 6/1 7/1 8/1\nf 1//1 2//1 6//1 5//1\nf 2/1/1 3/1/1 7/1/1 6/1/1\nf -5 -1 -2 -6\nf -8 -4 -1 -5\n";

fn cube() -> Mesh {
    read_mesh(CUBE_OBJ.as_bytes(), "cube.obj").unwrap()
}

#[test]
fn obj_quads_are_fan_triangulated() {
    let m = cube();
    assert_eq!(m.vertices.len(), 8);
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(m.triangles[0], [0, 3, 2]);
    assert_eq!(m.triangles[1], [0, 2, 1]);
    // "f -5 -1 -2 -6" with 8 vertices = 4 8 7 3 (1-based).
    assert_eq!(m.triangles[8], [3, 7, 6]);
    assert!((m.surface_area() - 6.0).abs() < 1e-12);
}

#[test]
fn obj_lines_ending_in_a_backslash_continue_on_the_next() {
    let cube = cube();
    // a face and a vertex split over lines (CRLF on one), a comment ending in a backslash kept apart
    let split = CUBE_OBJ
        .replace("f 1 4 3 2\n", "f 1 4 \\\n  3 \\\r\n 2\n")
        .replace("v -0.5 0.5 0.5\n", "# not continued \\\nv -0.5 \\\n0.5 0.5\n");
    let m = read_mesh(split.as_bytes(), "cube.obj").unwrap();
    assert_eq!((m.vertices, m.triangles), (cube.vertices, cube.triangles));
}

#[test]
fn off_variants_read_the_same_cube() {
    let cube = cube();
    let verts: String = cube.vertices.iter().map(|v| format!("{} {} {}\n", v[0], v[1], v[2])).collect();
    let coloured: String = cube.vertices.iter().map(|v| format!("{} {} {} 255 0 0 255\n", v[0], v[1], v[2])).collect();
    let faces = "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 3 7 6 2\n4 0 4 7 3\n";
    let coloured_faces = faces.replace('\n', " 1 0 0\n");
    let variants = [
        format!("OFF\n8 6 12\n{verts}{faces}"),
        format!("# comment\nOFF 8 6 12 # counts on the header line\n\n{verts}{faces}"),
        format!("COFF\n8 6 0\n{coloured}{coloured_faces}"),
        format!("OFF8 6 0\r\n{}{}", verts.replace('\n', "\r\n"), faces.replace('\n', "\r\n")),
        format!("OFF\n8 6 0\n{verts}{}", faces.replace(' ', "\n")),
    ];
    for text in variants {
        let m = read_mesh(text.as_bytes(), "cube.off").unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(m.vertices, cube.vertices);
        assert_eq!(m.triangles.len(), 12);
        assert!((m.surface_area() - 6.0).abs() < 1e-12);
    }
}

#[test]
fn stl_ascii_and_binary_agree() {
    let m = cube();
    let mut ascii = String::from("solid cube\n");
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for t in &m.triangles {
        ascii += "  facet normal 0 0 0\n    outer loop\n";
        binary.extend_from_slice(&[0u8; 12]);
        for &i in t {
            let v = m.vertices[i as usize];
            ascii += &format!("      vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]);
            for c in v {
                binary.extend_from_slice(&c.to_le_bytes());
            }
        }
        ascii += "    endloop\n  endfacet\n";
        binary.extend_from_slice(&[0u8; 2]);
    }
    ascii += "endsolid cube\n";
    let a = read_mesh(ascii.as_bytes(), "cube.stl").unwrap();
    let b = read_mesh(&binary, "cube.stl").unwrap();
    assert_eq!(a, b);
    assert_eq!(a.vertices.len(), 8, "corners merged");
    assert!((a.surface_area() - 6.0).abs() < 1e-12);
}

#[test]
fn cube_samples_lie_on_the_surface_and_are_deterministic() {
    let m = cube();
    let s = m.sample_surface(6000, 42).unwrap();
    assert_eq!(s.len(), 6000);
    assert_eq!(s, m.sample_surface(6000, 42).unwrap());
    assert_ne!(s, m.sample_surface(6000, 43).unwrap());
    let mut per_face = [0usize; 6];
    for p in &s.points {
        let on: Vec<usize> = (0..3).filter(|&a| p[a].abs() == 0.5).collect();
        assert!(!on.is_empty(), "{p:?} is not on the cube surface");
        assert!(p.iter().all(|v| v.abs() <= 0.5));
        let a = on[0];
        per_face[2 * a + (p[a] > 0.0) as usize] += 1;
    }
    // Equal areas: about 1000 samples per face (binomial sd ~ 29).
    for n in per_face {
        assert!((850..1150).contains(&n), "{per_face:?}");
    }
}

#[test]
fn sampling_is_area_weighted_and_uniform_inside_a_triangle() {
    // Two triangles, areas 1 and 3 (in the plane z = 0 and z = 1).
    let m = Mesh {
        vertices: vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [3.0, 0.0, 1.0],
            [0.0, 2.0, 1.0],
        ],
        triangles: vec![[0, 1, 2], [3, 4, 5], [0, 0, 1]],
    };
    assert!((m.surface_area() - 4.0).abs() < 1e-12);
    let s = m.sample_surface(20000, 1).unwrap();
    let upper = s.points.iter().filter(|p| p[2] == 1.0).count();
    let frac = upper as f64 / 20000.0;
    assert!((frac - 0.75).abs() < 0.02, "{frac}");
    // Uniform inside the big triangle: mean = centroid (1, 2/3).
    let big: Vec<_> = s.points.iter().filter(|p| p[2] == 1.0).collect();
    let mx = big.iter().map(|p| p[0] as f64).sum::<f64>() / big.len() as f64;
    let my = big.iter().map(|p| p[1] as f64).sum::<f64>() / big.len() as f64;
    assert!((mx - 1.0).abs() < 0.02 && (my - 2.0 / 3.0).abs() < 0.02, "{mx} {my}");
    // Every sample inside its triangle: x/3 + y/2 <= 1.
    assert!(big.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0 && p[0] as f64 / 3.0 + p[1] as f64 / 2.0 <= 1.0 + 1e-6));
}

#[test]
fn sampling_errors() {
    let flat = Mesh { vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], triangles: vec![[0, 1, 2]] };
    assert_eq!(flat.surface_area(), 0.0);
    let e = flat.sample_surface(10, 0).unwrap_err().to_string();
    assert!(e.contains("positive, finite area"), "{e}");
    assert!(Mesh::default().sample_surface(10, 0).is_err());
    let nan = Mesh { vertices: vec![[f32::NAN; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], triangles: vec![[0, 1, 2]] };
    assert!(nan.sample_surface(10, 0).is_err());
    let bad = Mesh { vertices: vec![[0.0; 3]], triangles: vec![[0, 0, 5]] };
    let e = bad.sample_surface(10, 0).unwrap_err().to_string();
    assert!(e.contains("triangle 0") && e.contains("out of range"), "{e}");
    assert!(cube().sample_surface(0, 0).unwrap().is_empty());
}

#[test]
fn faces_with_fewer_than_three_corners_are_dropped() {
    let m = read_mesh(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\nl 1 2\n", "a.obj").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
}
