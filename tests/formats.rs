//! Model formats (issue 17): PLY, OBJ with MTL, the `file` key, a model file alone (glTF: tests/formats_gltf.rs).

mod common;

use common::formats::*;
use common::*;
use glam::DVec3;
use lambert::Scene;
use lambert::loading::{NormalMode, load_mesh};

/// The bunny scene with its mesh read from `file` (relative to
/// assets/scenes), through the `file` key.
fn bunny_from(file: &str) -> Scene {
    let text = std::fs::read_to_string(asset("scenes/bunny.toml"))
        .unwrap()
        .replace(
            "obj = \"meshes/bunny_lowres.obj\"",
            &format!("file = \"{file}\""),
        );
    assert!(text.contains(file));
    scene(&text)
}

#[test]
fn ply_and_obj_give_the_same_image_bit_for_bit_on_both_paths() {
    let obj = bunny_from("meshes/bunny_lowres.obj");
    for ply in [
        "meshes/bunny_lowres.ply",
        "meshes/bunny_lowres_ascii.ply.gz",
    ] {
        let ply = bunny_from(ply);
        assert_eq!(obj.triangles(), ply.triangles());
        assert_eq!(obj.normals(), ply.normals(), "smooth normals");
        assert_eq!(bits(&render_cpu(&obj)), bits(&render_cpu(&ply)));
        assert_eq!(bits(&render_gpu(&obj)), bits(&render_gpu(&ply)));
    }
}

#[test]
fn ply_encodings_types_and_lists() {
    let dir = tempfile::tempdir().unwrap();
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\ncomment two triangles as a quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n\
             element edge 1\nproperty int vertex1\nproperty int vertex2\n\
             element face 1\nproperty list ushort short vertex_index\nproperty list uchar float texcoord\nend_header\n"
        )
    };
    let vertices = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut ascii = header("ascii");
    for v in vertices {
        ascii += &format!("{} {} {} 0 0 1 255\n", v[0], v[1], v[2]);
    }
    ascii += "0 1\n4 0 1 2 3 2 0.5 0.5\n";
    let mut big = header("binary_big_endian").into_bytes();
    let mut little = header("binary_little_endian").into_bytes();
    for (out, be) in [(&mut big, true), (&mut little, false)] {
        let f = |x: f32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        for v in vertices {
            for c in v.into_iter().chain([0.0, 0.0, 1.0]) {
                out.extend(f(c));
            }
            out.push(255);
        }
        let i32b = |x: i32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        out.extend(i32b(0));
        out.extend(i32b(1));
        let u16b = |x: u16| if be { x.to_be_bytes() } else { x.to_le_bytes() };
        out.extend(u16b(4));
        for i in [0i16, 1, 2, 3] {
            out.extend(if be { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out.push(2);
        out.extend(f(0.5));
        out.extend(f(0.5));
    }
    for (name, bytes) in [
        ("a.ply", ascii.into_bytes()),
        ("be.ply", big),
        ("le.ply", little),
    ] {
        let path = write(dir.path(), name, bytes);
        let mesh = load_mesh(&path, NormalMode::Smooth).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]], "{name}");
        assert_eq!(mesh.positions[2], DVec3::new(1.0, 1.0, 0.0), "{name}");
        assert!(mesh.file_normals, "{name}");
        assert_eq!(mesh.normals.unwrap()[1], [DVec3::Z; 3], "{name}");
    }
}

#[test]
fn malformed_ply_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let ok_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let binary_header = |vertices: u64| {
        format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut truncated = binary_header(3).into_bytes();
    truncated.extend([0u8; 36]);
    truncated.extend([3u8, 0, 0, 0, 0]);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("not.ply", b"plx\nformat ascii 1.0\n".to_vec(), "not.ply:1: not a PLY file"),
        ("format.ply", b"ply\nformat binary_middle_endian 1.0\nend_header\n".to_vec(), "format.ply:2: unknown format line"),
        ("noend.ply", b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(), "no end_header"),
        ("type.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n".to_vec(), "type.ply:4: unknown property type 'quad'"),
        ("range.ply", format!("{ok_header}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").into_bytes(), "range.ply:13: face 0: vertex index 3 is out of range"),
        ("nan.ply", format!("{ok_header}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").into_bytes(), "nan.ply:11: vertex 1: coordinate NaN must be finite"),
        ("huge.ply", format!("{ok_header}0 0 0\n1 1e30 0\n0 1 0\n3 0 1 2\n").into_bytes(), "vertex 1: coordinate 1000000000000000000000000000000 must be finite"),
        ("word.ply", format!("{ok_header}0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n").into_bytes(), "word.ply:11: vertex 1: 'x' is not a number"),
        ("short.ply", format!("{ok_header}0 0 0\n1 0 0\n").into_bytes(), "only 2 lines follow"),
        ("truncated.ply", truncated, "face 0: the file ends inside it"),
        ("claims.ply", { let mut b = binary_header(4_000_000_000).into_bytes(); b.extend([0u8; 64]); b }, "declares 4000000000 'vertex' elements"),
        ("points.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(), "points.ply: no triangles (1 points, 0 lines skipped)"),
        ("noxyz.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n".to_vec(), "no 'z' property"),
        ("two.ply", format!("{ok_header}0 0 0\n1 0 0\n0 1 0\n2 0 1\n").into_bytes(), "a face needs at least 3 vertices"),
        ("gz.ply.gz", b"not gzip".to_vec(), "not a readable gzip file"),
    ];
    assert_load_errors(dir.path(), cases, 5);
}

/// Issue 28 item 11: a face element declared before the vertex element
/// loads (indices are checked once every element is read); an ascii line
/// with more values than the header declares (VCGLib writes them) reads
/// the declared ones with one warning naming the first line; elements and
/// properties lambert does not read are named in one warning.
#[test]
fn ply_faces_first_extra_values_and_unread_properties() {
    let dir = tempfile::tempdir().unwrap();
    let faces_first = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
             element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        )
    };
    let ascii = faces_first("ascii") + "3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
    let mut binary = faces_first("binary_little_endian").into_bytes();
    binary.push(3);
    for i in [0i32, 1, 2] {
        binary.extend(i.to_le_bytes());
    }
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        binary.extend(c.to_le_bytes());
    }
    // 64-bit integers (trimesh reads them): a vertex id, skipped, and the
    // indices.
    let mut wide = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty int64 id\n\
                     property float x\nproperty float y\nproperty float z\n\
                     element face 1\nproperty list uchar uint64 vertex_indices\nend_header\n"
        .to_vec();
    for (id, v) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .enumerate()
    {
        wide.extend((-(id as i64)).to_be_bytes());
        for c in v {
            wide.extend(c.to_be_bytes());
        }
    }
    wide.push(3);
    for i in [0u64, 1, 2] {
        wide.extend(i.to_be_bytes());
    }
    let mesh = load_mesh(&write(dir.path(), "wide.ply", wide), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], DVec3::Y);

    for (name, bytes) in [("first.ply", ascii.into_bytes()), ("first-le.ply", binary)] {
        let mesh = load_mesh(&write(dir.path(), name, bytes), NormalMode::Face).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]], "{name}");
        assert_eq!(mesh.positions[1], DVec3::X, "{name}");
        assert!(mesh.warnings.is_empty(), "{name}: {:?}", mesh.warnings);
    }
    // An index past the vertices is still an error, at the face's line.
    let beyond = faces_first("ascii") + "3 0 1 3\n0 0 0\n1 0 0\n0 1 0\n";
    let message = error_of(&write(dir.path(), "beyond.ply", beyond));
    assert!(
        message.contains(
            "beyond.ply:10: face 0: vertex index 3 is out of range: the file has 3 vertices"
        ),
        "{message}"
    );

    let surplus = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                   element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                   0 0 0\n1 0 0 0.5 0.5\n0 1 0 1 1\n3 0 1 2 6 0 0 1 0 0 1\n";
    let mesh = load_mesh(&write(dir.path(), "surplus.ply", surplus), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], DVec3::Y);
    assert_has(
        only_warning(&mesh),
        &[
            "surplus.ply:11: vertex 1: 5 values on the line, the header declares 3",
            "ignored (on 3 lines in all)",
        ],
    );

    let extra = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                 property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nproperty uchar flags\n\
                 element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n\
                 0 0 0 255\n1 0 0 255\n0 1 0 255\n3 0 1 2 7\n0 1\n";
    let mesh = load_mesh(&write(dir.path(), "extra.ply", extra), NormalMode::Face).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_has(
        only_warning(&mesh),
        &["extra.ply: ignored", "vertex red, face flags, element edge"],
    );
}

#[test]
fn obj_materials_from_mtl_files() {
    let (dir, mesh) = load_written(&[
        (
            "colours.mtl",
            "# made by hand\nnewmtl red.paint-1\nKd 0.8 0.1 0.1\nnewmtl blue\nKa 0 0 0\nKd 0.1 0.1 0.9\n",
        ),
        (
            "boxes.obj",
            "mtllib colours.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nusemtl red.paint-1\nf 2 4 3\nusemtl blue\nf 1 3 2\nusemtl nonesuch\nf 2 3 4\n",
        ),
    ]);
    let d = dir.path();
    assert_eq!(mesh.face_materials, vec![None, Some(0), Some(1), None]);
    assert_eq!(albedos(&mesh), vec![[0.8, 0.1, 0.1], [0.1, 0.1, 0.9]]);
    let warnings = mesh.warnings.join("\n");
    assert!(warnings.contains("missing.mtl"), "{warnings}");
    assert!(
        warnings.contains("boxes.obj:11: unknown material 'nonesuch'"),
        "{warnings}"
    );

    let camera = "[camera]\neye = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n[render]\nambient = 1.0\nshadows = false\n";
    let scene_at = |extra: &str| {
        let text = format!("{camera}[[mesh]]\nfile = \"boxes.obj\"\n{extra}");
        Scene::from_toml(&text, &d.join("s.toml")).unwrap()
    };
    let s = scene_at("");
    let albedo = |t: usize| s.materials()[s.triangles()[t].material as usize].albedo();
    assert_eq!(
        [albedo(0), albedo(1), albedo(2), albedo(3)],
        [[0.8; 3], [0.8, 0.1, 0.1], [0.1, 0.1, 0.9], [0.8; 3]]
    );
    assert_eq!(s.warnings().len(), 2);
    let overridden = scene_at("albedo = [0.2, 0.3, 0.4]\n");
    assert!(
        overridden
            .triangles()
            .iter()
            .all(|t| overridden.materials()[t.material as usize].albedo() == [0.2, 0.3, 0.4])
    );
    // Per-face materials on both paths: ambient 1 shows each face's albedo.
    let (gpu, cpu) = (render_gpu(&s), render_cpu(&s));
    assert_eq!(gpu.prims, cpu.prims);
    let stats = lambert::diff::compare(&gpu, &cpu, &Default::default()).unwrap();
    assert!(stats.passed, "{stats}");
    let reds = cpu
        .image
        .rgb
        .iter()
        .filter(|p| **p == [0.8, 0.1, 0.1])
        .count();
    assert!(reds > 0, "no pixel shows the red material");

    for (mtl, expected) in [
        (
            "newmtl a\nKd 0.5 0.5\n",
            "bad.mtl:2: Kd needs 1 or 3 numbers (r [g b]), found 2",
        ),
        (
            "newmtl a\nKd 0.5 x 0.5\n",
            "bad.mtl:2: Kd: 'x' is not a number",
        ),
        (
            "newmtl a\nKd 0.5 -1 0.5\n",
            "bad.mtl:2: Kd: -1 must be finite and non-negative",
        ),
        ("Kd 1 1 1\n", "bad.mtl:1: Kd before any newmtl"),
    ] {
        write(d, "bad.mtl", mtl);
        write(
            d,
            "bad.obj",
            "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let message = error_of(&d.join("bad.obj"));
        assert!(message.contains(expected), "{message}");
    }
}

/// `lambert render MODEL` for every format, with no scene file: a framed
/// camera or the file's, a light, never a black picture; `--camera` picks
/// a glTF camera by name; an unknown extension names the supported ones.
#[test]
fn a_model_file_alone_renders() {
    let dir = tempfile::tempdir().unwrap();
    for model in [
        "bunny_lowres.obj",
        "bunny_lowres.ply",
        "bunny_lowres_ascii.ply.gz",
        "boxes.glb",
    ] {
        let out = dir.path().join(format!("{model}.png"));
        let output = lambert_command()
            .args([
                "render",
                meshes(model).to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--width",
                "64",
            ])
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{model}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let image = image::open(&out).unwrap().to_rgb8();
        assert_eq!(image.width(), 64);
        assert_eq!(image.height(), 48, "{model}: the aspect ratio is kept");
        let lit = image
            .pixels()
            .filter(|p| p.0.iter().any(|&c| c > 40))
            .count();
        assert!(lit > 64 * 48 / 10, "{model}: only {lit} lit pixels");
    }
    let output = lambert_command()
        .args([
            "render",
            meshes("boxes.glb").to_str().unwrap(),
            "-o",
            "x.png",
            "--camera",
            "nonesuch",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(
        text.contains("no perspective camera named 'nonesuch' (the file has 'view')"),
        "{text}"
    );
    // STL is read since issue 30; a 3DS file is not.
    let other = write(dir.path(), "model.3ds", "MM");
    let message = Scene::load(&other).unwrap_err().to_string();
    assert!(
        message.contains(".obj, .ply, .ply.gz, .gltf, .glb and .stl"),
        "{message}"
    );
    let output = lambert_command()
        .args(["info", meshes("boxes.glb").to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    for expected in [
        "triangles: 14",
        "materials: 2",
        "lights: 2",
        "eye [0, 2.5, 7]",
    ] {
        assert!(text.contains(expected), "info lacks {expected}: {text}");
    }
}

/// OBJ's `\` line continuation (the OBJ spec): a statement across lines
/// reads as one, and errors after it still name the right line.
#[test]
fn obj_line_continuation() {
    let text = "v 0 0 \\\n0\nv 1 0 0\r\nv 0 1 0\nv 1 1 0\nf 1 \\\r\n 2 \\ \n3\nf 2 4 3\n";
    let (dir, mesh) = load_written(&[("c.obj", text)]);
    let d = dir.path();
    assert_eq!(mesh.positions[0], DVec3::ZERO);
    assert_eq!(mesh.positions.len(), 4);
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    assert!(mesh.warnings.is_empty(), "{:?}", mesh.warnings);
    let bad = write(d, "bad.obj", format!("{text}v 0 0 x\n"));
    let message = error_of(&bad);
    assert!(
        message.contains("bad.obj:10: 'x' is not a number"),
        "{message}"
    );
    // A continuation on the last line ends the statement there.
    let last = write(d, "last.obj", format!("{text}f 1 2 4 \\"));
    assert_eq!(
        load_mesh(&last, NormalMode::Face).unwrap().triangles.len(),
        3
    );
}

/// Faces that other readers load with a note: fewer than 3 vertices
/// (skipped), normals that are not defined (dropped for computed ones);
/// one warning per kind, with the count and the first line.
#[test]
fn obj_short_faces_and_undefined_normals_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let quad = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\n";
    let short = write(d, "short.obj", format!("{quad}f 1 2\nf 1 2 3\nf 4\nf\n"));
    let mesh = load_mesh(&short, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        mesh.warnings,
        vec![format!(
            "{}:5: 3 faces with fewer than 3 vertices skipped (the first on this line)",
            short.display()
        )]
    );

    let faces = |second: &str, third: &str| {
        format!("{quad}vn 0 0 1\nf 1//1 2//1 3//1\nf {second}\nf {third}\n")
    };
    let named = write(d, "named.obj", faces("2//2 4//2 3//2", "2//1 4//-3 3//1"));
    let plain = write(d, "plain.obj", faces("2 4 3", "2 4 3"));
    let mesh = load_mesh(&named, NormalMode::Smooth).unwrap();
    let reference = load_mesh(&plain, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles, reference.triangles);
    assert_eq!(mesh.normals, reference.normals);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], [DVec3::Z; 3]);
    assert!(!mesh.file_normals);
    assert_eq!(mesh.warnings.len(), 1, "{:?}", mesh.warnings);
    assert!(
        mesh.warnings[0].starts_with(&format!(
            "{}:7: 2 faces naming normals that are not defined",
            named.display()
        )),
        "{:?}",
        mesh.warnings
    );
    // No vn at all: the face loads, with computed normals.
    let none = write(d, "none.obj", format!("{quad}f 1//1 2//1 3//1\n"));
    let mesh = load_mesh(&none, NormalMode::Smooth).unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert!(mesh.warnings[0].contains("none.obj:5: 1 face naming normals"));
    // A normal index that is not a number is still an error.
    let word = write(d, "word.obj", format!("{quad}f 1//x 2//1 3//1\n"));
    assert!(error_of(&word).contains("word.obj:5: 'x' is not a normal index"));
}

/// MTL colours as the spec writes them: `Kd r` (g and b repeat r),
/// `Kd xyz X [Y Z]` (CIE XYZ, converted to linear sRGB), `Kd spectral`
/// (a warning, the default albedo); negative values stay refused.
#[test]
fn mtl_grey_xyz_and_spectral_colours() {
    let names = ["grey", "spectral", "white", "red", "greyxyz", "beyond"];
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for name in names {
        obj += &format!("usemtl {name}\nf 1 2 3\n");
    }
    let mtl = "newmtl grey\nKd 0.5\nnewmtl spectral\nKd spectral green.rfl 0.8\n\
               newmtl white\nKd xyz 0.95047 1.0 1.08883\nnewmtl red\nKd xyz 0.4124564 0.2126729 0.0193339\n\
               newmtl greyxyz\nKd xyz 0.2\nnewmtl beyond\nKd xyz 1 0 0\n";
    let (dir, mesh) = load_written(&[("m.mtl", mtl), ("m.obj", &obj)]);
    let d = dir.path();
    let m = &albedos(&mesh);
    assert_eq!(m[0], [0.5; 3]);
    assert_eq!(m[1], [0.8; 3]);
    let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-4);
    assert!(close(m[2], [1.0; 3]), "D65 white: {:?}", m[2]);
    assert!(close(m[3], [1.0, 0.0, 0.0]), "sRGB red: {:?}", m[3]);
    // Y = Z = X: equal XYZ is not grey in sRGB (D65 white is not X=Y=Z).
    assert!(m[4][0] > m[4][1] && m[4][1] > m[4][2], "{:?}", m[4]);
    assert!(m[5][1] == 0.0 && m[5][0] > 3.0, "{:?}", m[5]);
    let warnings = mesh.warnings.join("\n");
    assert!(
        warnings.contains("m.mtl:4: Kd spectral is not supported"),
        "{warnings}"
    );
    assert!(warnings.contains("m.mtl:12: Kd xyz"), "{warnings}");
    assert_eq!(mesh.warnings.len(), 2, "{warnings}");

    for (mtl, expected) in [
        (
            "newmtl a\nKd -0.5\n",
            "n.mtl:2: Kd: -0.5 must be finite and non-negative",
        ),
        (
            "newmtl a\nKd xyz 0.5 -1\n",
            "n.mtl:2: Kd: -1 must be finite and non-negative",
        ),
        (
            "newmtl a\nKd xyz\n",
            "n.mtl:2: Kd needs 1 or 3 numbers (r [g b]), found 0",
        ),
    ] {
        write(d, "n.mtl", mtl);
        let obj = write(
            d,
            "n.obj",
            "mtllib n.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let message = error_of(&obj);
        assert!(message.contains(expected), "{message}");
    }
}

/// A TOML mesh scaled by a negative factor on one or three axes is
/// mirrored: its faces keep facing out (two corners swapped, and their
/// normals with them); on two axes it is a rotation and nothing swaps.
#[test]
fn toml_mirrored_meshes_keep_their_normals_facing_out() {
    let dir = tempfile::tempdir().unwrap();
    // A tetrahedron whose faces all face out.
    std::fs::write(
        dir.path().join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1//1 3//1 2//1\nf 1//1 2//1 4//1\nf 1//1 4//1 3//1\nf 2//1 3//1 4//1\n",
    )
    .unwrap();
    for (scale, mirrored) in [
        ("[-1.0, 1.0, 1.0]", true),
        ("[1.0, -2.0, 1.0]", true),
        ("-1.0", true),
        ("[-1.0, -1.0, 1.0]", false),
        ("1.0", false),
    ] {
        let text = format!(
            "[camera]\neye = [3.0, 3.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\nwidth = 8\nheight = 8\n\
             [[mesh]]\nfile = \"tet.obj\"\nnormals = \"smooth\"\nscale = {scale}\n\
             [[point_light]]\nposition = [0.0, 5.0, 0.0]\nintensity = 1.0\n"
        );
        let s = Scene::from_toml(&text, &dir.path().join("s.toml")).unwrap();
        assert_eq!(s.triangles().len(), 4, "{scale}");
        let v = |p: [f32; 3]| DVec3::from(p.map(f64::from));
        let corners: Vec<DVec3> = s
            .triangles()
            .iter()
            .flat_map(|t| [v(t.v0), v(t.v1), v(t.v2)])
            .collect();
        let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
        for t in s.triangles() {
            let [a, b, c] = [v(t.v0), v(t.v1), v(t.v2)];
            let outward = (a + b + c) / 3.0 - centre;
            assert!(
                (b - a).cross(c - a).dot(outward) > 0.0,
                "{scale}: {t:?} faces in"
            );
        }
        // The first face (1, 3, 2) keeps its first corner; a mirror swaps the others.
        let first = &s.triangles()[0];
        let expected_v1 = if mirrored { v(first.v2) } else { v(first.v1) };
        assert_eq!(v(first.v0), DVec3::ZERO, "{scale}");
        assert!(
            expected_v1.x == 0.0 && expected_v1.z == 0.0,
            "{scale}: {first:?}"
        );
        assert_eq!(s.normals().len(), 4, "{scale}: smooth normals kept");
    }
}
