//! STL (issue 30 item 5): binary = ASCII = OBJ, `solid` headers, several solids, the size rule, errors, allocation.

mod common;

use std::path::{Path, PathBuf};

use common::formats::{assert_has, assert_load_errors};
use common::*;
use glam::DVec3;
use lambert::Scene;
use lambert::loading::{NormalMode, load_mesh};

// Counts the heap, for the test that a huge count allocates nothing.
#[global_allocator]
static ALLOCATOR: lambert::memory::Counting = lambert::memory::Counting;

type Facet = [[f32; 3]; 3];

/// A binary STL: `header` (padded to 80 bytes), `count`, the facets (each
/// with a normal of 0 and attribute bytes 0xBEEF, which are not read).
fn binary(header: &[u8], count: u32, facets: &[Facet]) -> Vec<u8> {
    let mut bytes = header.to_vec();
    bytes.resize(80, b' ');
    bytes.extend(count.to_le_bytes());
    for facet in facets {
        bytes.extend([0u8; 12]);
        for c in facet.iter().flatten() {
            bytes.extend(c.to_le_bytes());
        }
        bytes.extend(0xBEEFu16.to_le_bytes());
    }
    bytes
}

/// A number as text that parses back to exactly `x` (f32 values are f64s).
fn text(x: f32) -> String {
    format!("{}", x as f64)
}

/// One ASCII solid of `facets`, with a normal that is wrong on purpose
/// (normals are not read).
fn solid(name: &str, facets: &[Facet]) -> String {
    let mut s = format!("solid {name}\n");
    for facet in facets {
        s += "  facet normal 0 0 -1\n    outer loop\n";
        for v in facet {
            s += &format!(
                "      vertex {} {} {}\n",
                text(v[0]),
                text(v[1]),
                text(v[2])
            );
        }
        s += "    endloop\n  endfacet\n";
    }
    s + &format!("endsolid {name}\n")
}

/// The bundled bunny's triangles, its coordinates rounded to f32 (what a
/// binary STL holds).
fn bunny_facets() -> Vec<Facet> {
    let mesh = load_mesh(&asset("scenes/meshes/bunny_lowres.obj"), NormalMode::Face).unwrap();
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize].as_vec3().to_array()))
        .collect()
}

/// The triangles as an OBJ: a vertex per corner, as STL stores them.
fn obj(facets: &[Facet]) -> String {
    let mut s = String::new();
    for v in facets.iter().flatten() {
        s += &format!("v {} {} {}\n", text(v[0]), text(v[1]), text(v[2]));
    }
    for i in 0..facets.len() {
        s += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    s
}

/// A scene of the model file `file` in `dir`, shaded smooth, lit by a
/// point and a directional light, with shadows.
fn scene_of_file(dir: &Path, file: &str) -> Scene {
    let toml = format!(
        "[camera]\neye = [8.0, 9.0, 16.0]\nlook_at = [0.0, 4.0, 0.0]\nvfov = 40.0\nwidth = 96\nheight = 96\n\
         [[mesh]]\nfile = \"{file}\"\nnormals = \"smooth\"\n\
         [[point_light]]\nposition = [-8.0, 14.0, 10.0]\nintensity = 700.0\n\
         [[directional_light]]\ndirection = [-0.6, -1.0, 0.5]\nirradiance = 0.3\n"
    );
    Scene::from_toml(&toml, &dir.join("scene.toml")).unwrap()
}

/// The bunny as binary STL, ASCII STL and OBJ (the same f32 coordinates):
/// the same scene triangles and smooth normals bit for bit, and the same
/// image on both paths.
#[test]
fn binary_ascii_and_obj_of_the_same_triangles_are_the_same_scene() {
    let dir = tempfile::tempdir().unwrap();
    let facets = bunny_facets();
    let n = facets.len() as u32;
    write(dir.path(), "b.stl", binary(b"binary bunny", n, &facets));
    write(dir.path(), "a.stl", solid("bunny", &facets));
    write(dir.path(), "o.obj", obj(&facets));
    let reference = scene_of_file(dir.path(), "o.obj");
    assert_eq!(reference.triangles().len(), 3674);
    for file in ["b.stl", "a.stl"] {
        let stl = scene_of_file(dir.path(), file);
        assert_eq!(stl.triangles(), reference.triangles(), "{file}");
        assert!(!stl.normals().is_empty(), "{file}: smooth");
        // The OBJ's corners are apart too, so its smooth normals are face
        // normals; the STL's are welded, so they differ from the OBJ's...
        assert_ne!(stl.normals(), reference.normals(), "{file}: welded");
        assert!(stl.warnings().is_empty(), "{file}: {:?}", stl.warnings());
    }
    // ...and agree with the bundled OBJ, whose vertices are shared.
    let welded = load_mesh(&dir.path().join("b.stl"), NormalMode::Smooth).unwrap();
    let shared = load_mesh(&asset("scenes/meshes/bunny_lowres.obj"), NormalMode::Smooth).unwrap();
    assert_eq!(welded.positions.len(), shared.positions.len());
    for (w, s) in welded.normals.unwrap().iter().zip(shared.normals.unwrap()) {
        for k in 0..3 {
            let angle = w[k].angle_between(s[k]);
            assert!(angle < 1e-5, "welded normal {} vs {}", w[k], s[k]);
        }
    }
    // Face normals (a model file alone): the same image, bit for bit.
    let face = |file: &str| Scene::load(&dir.path().join(file)).unwrap();
    let obj_scene = face("o.obj");
    for file in ["b.stl", "a.stl"] {
        let stl = face(file);
        assert_eq!(stl.triangles(), obj_scene.triangles(), "{file}");
        assert_eq!(stl.normals(), obj_scene.normals(), "{file}");
        assert_eq!(
            bits(&render_cpu(&stl)),
            bits(&render_cpu(&obj_scene)),
            "{file}"
        );
        assert_eq!(
            bits(&render_gpu(&stl)),
            bits(&render_gpu(&obj_scene)),
            "{file}"
        );
    }
    // And with the smooth scenes: the binary and ASCII STL render alike.
    let binary_scene = scene_of_file(dir.path(), "b.stl");
    let ascii_scene = scene_of_file(dir.path(), "a.stl");
    assert_eq!(binary_scene.normals(), ascii_scene.normals());
    assert_eq!(
        bits(&render_cpu(&binary_scene)),
        bits(&render_cpu(&ascii_scene))
    );
    assert_eq!(
        bits(&render_gpu(&binary_scene)),
        bits(&render_gpu(&ascii_scene))
    );
}

const UNIT: [Facet; 2] = [
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.25]],
];

fn corners(path: &Path) -> Vec<[DVec3; 3]> {
    let mesh = load_mesh(path, NormalMode::Face).unwrap();
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect()
}

fn expected(facets: &[Facet]) -> Vec<[DVec3; 3]> {
    facets
        .iter()
        .map(|f| f.map(|v| DVec3::from(v.map(f64::from))))
        .collect()
}

/// SolidWorks and others begin binary headers with `solid`: the size
/// decides (84 + 50·n), even when the header looks like ASCII text.
#[test]
fn a_binary_file_whose_header_begins_with_solid() {
    let dir = tempfile::tempdir().unwrap();
    for header in [
        &b"solid part1"[..],
        b"SOLID",
        b"solid part\nfacet normal 0 0 1\n",
        b"solid x\nendsolid x\n",
    ] {
        let path = write(dir.path(), "sw.stl", binary(header, 2, &UNIT));
        let mesh = load_mesh(&path, NormalMode::Face).unwrap();
        assert!(mesh.warnings.is_empty(), "{:?}", mesh.warnings);
        assert_eq!(corners(&path), expected(&UNIT));
    }
    // With a count that disagrees with its size: not ASCII either (it
    // does not parse as ASCII, and holds bytes text does not), so the size
    // rule reads it, with a warning.
    for header in [&b"solid part1"[..], b"solid x\nendsolid x\n"] {
        let path = write(dir.path(), "swcount.stl", binary(header, 0, &UNIT));
        let mesh = load_mesh(&path, NormalMode::Face).unwrap();
        assert_eq!(corners(&path), expected(&UNIT));
        assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
        assert!(mesh.warnings[0].contains("swcount.stl"));
        assert!(mesh.warnings[0].contains("declares 0 triangles"));
    }
}

/// An ASCII file of several solids (mixed case, CRLF, blank lines, names
/// with spaces): every solid's facets, in file order.
#[test]
fn several_solids_are_read_in_file_order() {
    let dir = tempfile::tempdir().unwrap();
    let second: [Facet; 1] = [[[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.5, -2.0]]];
    let text = solid("first part", &UNIT[..1])
        + "\n\n"
        + &solid("Second", &second).to_uppercase()
        + &solid("", &UNIT[1..]);
    let text = text.replace('\n', "\r\n");
    let path = write(dir.path(), "three.stl", &text);
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert!(mesh.warnings.is_empty(), "{:?}", mesh.warnings);
    assert_eq!(corners(&path), expected(&[UNIT[0], second[0], UNIT[1]]));
    // Facets are numbered on across solids: an error in the third solid
    // names facet 2 and its line.
    let broken = text.replace("vertex 0 1 0.25", "vertex 0 one 0.25");
    let path = write(dir.path(), "broken.stl", broken);
    let line = 1 + text
        .lines()
        .position(|l| l.contains("vertex 0 1 0.25"))
        .unwrap();
    let message = error_of(&path);
    let expected = format!("broken.stl:{line}: facet 2, vertex 2: 'one' is not a number");
    assert!(message.contains(&expected), "{message}");
    // A last solid without endsolid, and text after the last endsolid:
    // read, each with a warning naming the line.
    let open = solid("a", &UNIT);
    let open = open.trim_end().trim_end_matches("endsolid a");
    let path = write(dir.path(), "open.stl", open);
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert_eq!(mesh.warnings.len(), 1);
    assert!(mesh.warnings[0].contains("open.stl:1: the solid begun here has no endsolid"));
    let path = write(dir.path(), "tail.stl", solid("a", &UNIT) + "\n%%EOF\n");
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert!(
        mesh.warnings[0].contains("tail.stl:18: '%%EOF' after the last endsolid is ignored"),
        "{:?}",
        mesh.warnings
    );
}

/// A binary count that disagrees with the size: the size rules (whole
/// facets), or the count's facets when they fit and a remainder follows;
/// each a warning naming the file, the count and the size. A count the
/// file cannot hold, ending inside a facet, is an error.
#[test]
fn a_count_that_disagrees_with_the_size() {
    let dir = tempfile::tempdir().unwrap();
    let three = [UNIT[0], UNIT[1], UNIT[0]];
    let path = write(dir.path(), "zero.stl", binary(b"streamed", 0, &three));
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles.len(), 3);
    assert_eq!(
        mesh.warnings,
        [format!(
            "{}: its binary STL header declares 0 triangles (84 bytes in all), but the file has 234 bytes, \
             which hold 3 facets exactly: read 3, as the size says",
            path.display()
        )]
    );
    let path = write(dir.path(), "many.stl", binary(b"", 7, &three));
    assert_eq!(
        load_mesh(&path, NormalMode::Face).unwrap().triangles.len(),
        3
    );

    // Trailing bytes after the declared facets: the count's facets.
    let mut trailing = binary(b"", 2, &three);
    trailing.extend(b"\r\n");
    let path = write(dir.path(), "trailing.stl", trailing);
    let mesh = load_mesh(&path, NormalMode::Face).unwrap();
    assert_eq!(corners(&path), expected(&UNIT));
    assert_eq!(mesh.warnings.len(), 1);
    assert!(
        mesh.warnings[0].contains("declares 2 triangles (184 bytes in all), but the file has 236 bytes: read 2; the 52 bytes after them are ignored"),
        "{}",
        mesh.warnings[0]
    );

    // Truncated inside a facet.
    let mut cut = binary(b"", 3, &three);
    cut.truncate(84 + 50 * 2 + 30);
    let path = write(dir.path(), "cut.stl", cut);
    let message = error_of(&path);
    assert_has(
        &message,
        &[
            "cut.stl: its binary STL header declares 3 triangles (234 bytes in all), but the file has 214 bytes: it is truncated, ending at byte 214 inside facet 2",
        ],
    );
}

/// A count of four billion facets in a file of one facet, or of none
/// whole: nothing allocated for the count (the heap's peak stays small;
/// other tests run beside this one, hence the margin), a warning or an
/// error at once.
#[test]
fn a_huge_count_in_a_tiny_file_allocates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let one = write(dir.path(), "one.stl", binary(b"", u32::MAX, &UNIT[..1]));
    let mut cut = binary(b"", u32::MAX, &UNIT[..1]);
    cut.truncate(100);
    let cut = write(dir.path(), "cut.stl", cut);
    let before = lambert::memory::reset_peak();
    let start = std::time::Instant::now();
    let mesh = load_mesh(&one, NormalMode::Smooth).unwrap();
    let message = error_of(&cut);
    let peak = lambert::memory::peak() - before;
    assert!(start.elapsed().as_secs() < 1, "{:?}", start.elapsed());
    assert!(peak < 64 << 20, "peak heap {peak} bytes");
    assert_eq!(mesh.triangles.len(), 1);
    assert!(mesh.warnings[0].contains("declares 4294967295 triangles"));
    assert_has(&message, &["ending at byte 100 inside facet 0"]);
}

/// Broken files: errors naming the file and the byte (binary) or line
/// (ASCII), the facet and vertex, and what is wrong; never a panic, and
/// at once.
#[test]
fn malformed_stl_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let nan: [Facet; 2] = [
        UNIT[0],
        [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
    ];
    let huge: [Facet; 1] = [[[0.0, 0.0, 0.0], [0.0, 3e38, 0.0], [0.0, 1.0, 0.0]]];
    let good = solid("s", &UNIT);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("nan.stl", binary(b"", 2, &nan), "nan.stl: byte 158: facet 1, vertex 1: coordinate NaN must be finite"),
        ("huge.stl", binary(b"", 1, &huge), "huge.stl: byte 112: facet 0, vertex 1: coordinate 300000000000000000000000000000000000000 must be finite"),
        ("short.stl", b"\0\0\0\x01".to_vec(), "short.stl: not an STL file: it does not begin with 'solid' as ASCII STL does, and its 4 bytes are fewer than a binary STL's header (84)"),
        ("text.stl", b"this is a text file, long enough to hold a binary header if it were one, but it is not".to_vec(), "text.stl: not an STL file: it does not begin with 'solid' as ASCII STL does, and it is text"),
        ("cut.stl", good[..good.find("endloop").unwrap()].as_bytes().to_vec(), "cut.stl:7: facet 0: expected 'endloop' after three vertices (STL facets are triangles), the file ends inside it"),
        ("cutvertex.stl", good[..good.find("vertex 1 0 0").unwrap() + 10].as_bytes().to_vec(), "cutvertex.stl:5: facet 0, vertex 1: the file ends inside it"),
        ("quad.stl", good.replacen("    endloop", "      vertex 2 2 2\n    endloop", 1).into_bytes(), "quad.stl:7: facet 0: expected 'endloop' after three vertices (STL facets are triangles), found 'vertex'"),
        ("noloop.stl", good.replacen("outer loop", "outer", 1).into_bytes(), "noloop.stl:4: facet 0: expected 'loop' after 'outer', found 'vertex'"),
        ("nonormal.stl", good.replacen("facet normal 0 0 -1", "facet", 1).into_bytes(), "nonormal.stl:3: facet 0: expected 'normal' after 'facet', found 'outer'"),
        ("word.stl", good.replacen("endfacet", "endfacet\n  facets", 1).into_bytes(), "word.stl:9: expected 'facet' or 'endsolid', found 'facets'"),
        ("inf.stl", good.replacen("vertex 1 1 0", "vertex 1 inf 0", 1).into_bytes(), "inf.stl:6: facet 0, vertex 2: coordinate inf must be finite"),
        ("big.stl", good.replacen("vertex 1 1 0", "vertex 1 1e16 0", 1).into_bytes(), "big.stl:6: facet 0, vertex 2: coordinate 1e16 must be finite with magnitude at most 1e15"),
        ("empty.stl", b"solid Empty\nendsolid Empty\n".to_vec(), "empty.stl: no triangles (0 points, 0 lines skipped)"),
    ];
    assert_load_errors(dir.path(), cases, 1);
    // From the command line: exit status 1, the message on stderr.
    let path = dir.path().join("quad.stl");
    let output = lambert(&["info", s(&path)]);
    assert_eq!(output.status.code(), Some(1));
    assert_has(
        &stderr(&output),
        &["quad.stl:7: facet 0: expected 'endloop'"],
    );
}

/// Facets with no area (a point, a segment) are kept, as trimesh keeps
/// them: they count, the trees stay valid, and both paths render alike.
#[test]
fn degenerate_facets_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    let facets = [
        UNIT[0],
        [[0.5, 0.5, 0.5]; 3],
        [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]],
        UNIT[1],
    ];
    let path = write(dir.path(), "degenerate.stl", binary(b"", 4, &facets));
    let mesh = load_mesh(&path, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(
        mesh.triangles[1], [mesh.triangles[1][0]; 3],
        "one welded point"
    );
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.triangles().len(), 4);
    scene
        .bvh()
        .validate(scene.triangles(), scene.spheres())
        .unwrap();
    let compressed = lambert::cwbvh::compress(scene.bvh());
    lambert::cwbvh::validate(&compressed, scene.bvh()).unwrap();
    assert_eq!(bits(&render_cpu(&scene)), bits(&render_gpu(&scene)));
    let output = lambert(&["info", s(&path)]);
    assert!(String::from_utf8_lossy(&output.stdout).contains("triangles: 4"));
}

/// Smooth normals over welded positions: at each vertex of an
/// octahedron the sum of its four facets' normals, which points along the
/// vertex; -0 and +0 weld.
#[test]
fn smooth_normals_weld_identical_positions() {
    let dir = tempfile::tempdir().unwrap();
    let mut facets: Vec<Facet> = Vec::new();
    for sx in [1.0f32, -1.0] {
        for sy in [1.0f32, -1.0] {
            for sz in [1.0f32, -1.0] {
                let (a, b, c) = ([sx, 0.0, 0.0], [0.0, sy, 0.0], [0.0, 0.0, sz]);
                // Wound outwards: an odd number of mirrors swaps two.
                facets.push(if sx * sy * sz > 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                });
            }
        }
    }
    // One corner written as -0.
    facets[0][0] = [1.0, -0.0, -0.0];
    let path = write(dir.path(), "octahedron.stl", binary(b"", 8, &facets));
    let mesh = load_mesh(&path, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.positions.len(), 6, "welded");
    assert!(!mesh.file_normals);
    let normals = mesh.normals.as_ref().unwrap();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let p = mesh.positions[tri[k] as usize];
            let n = normals[t][k];
            assert!(n.normalize().angle_between(p) < 1e-12, "vertex {p}: {n}");
        }
    }
    // Face normals: none computed.
    assert!(
        load_mesh(&path, NormalMode::Face)
            .unwrap()
            .normals
            .is_none()
    );
}

/// Files lambert reads as STL: the extension in any case.
#[test]
fn the_extension_in_any_case() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.stl", "b.STL", "c.Stl"] {
        let path: PathBuf = write(dir.path(), name, binary(b"", 2, &UNIT));
        assert_eq!(Scene::load(&path).unwrap().triangles().len(), 2, "{name}");
    }
}

/// The malformed-file corpus (`fuzz/regressions/stl/`, replayed by the
/// fuzz harness and tests/reliability.rs): each `malformed-*` is an error
/// naming the file and a byte or line; each `accepted-*` loads, with a
/// warning.
#[test]
fn the_malformed_corpus_names_bytes_and_lines() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions/stl");
    let mut seen = [0, 0];
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let result = lambert::inputs::Input::Stl.parse(&std::fs::read(&path).unwrap(), &path);
        if name.starts_with("accepted-") {
            let mesh = load_mesh(&path, NormalMode::Face).unwrap();
            assert!(!mesh.triangles.is_empty(), "{name}");
            // A warning for each but the facet normals, which are not read.
            let warned = !mesh.warnings.is_empty();
            assert_eq!(
                warned,
                !name.contains("nan-normals"),
                "{name}: {:?}",
                mesh.warnings
            );
            result.unwrap();
            seen[0] += 1;
        } else {
            let message = result.unwrap_err().to_string();
            let at = format!("{}:", path.display());
            let located = message.starts_with(&at)
                && (message[at.len()..].starts_with(|c: char| c.is_ascii_digit())
                    || message.contains(": byte ")
                    || message.contains("not an STL file")
                    || message.contains("ending at byte"));
            assert!(located, "{name}: {message}");
            seen[1] += 1;
        }
    }
    assert!(seen[0] >= 5 && seen[1] >= 10, "{seen:?}");
}
