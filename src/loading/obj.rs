//! Wavefront OBJ loading, with its MTL materials (`Kd`, `Ke`, `d`/`Tr`
//! and their `map_` images; `Ks`, `Ns`, `Pr`, `Pm` as `mtl_brdf` maps
//! them), texture coordinates (`vt`, v flipped to glTF's
//! convention) and vertex colours (`v x y z r g b`).
//!
//! A small parser of our own rather than tobj: errors must name the file and
//! line at fault, and the triangle order must be exactly the file's (polygons
//! fan-triangulated as (v0,v1,v2), (v0,v2,v3), …), because primitive ids in
//! `lambert trace` output are defined by it.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::material::{AlphaMode, ImageSource, MaterialDesc, Sampler, TextureUse, Wrap};
use super::mtl_brdf::MtlSpecular;
use super::{Mesh, NormalMode, area_weighted_normals, check_coordinate, corner_values};
use crate::error::{Error, Result};

/// Reads an OBJ file and the MTL files it names.
pub fn load_obj(path: &Path, mode: NormalMode) -> Result<Mesh> {
    let text = crate::files::read_capped(path, crate::files::MAX_MODEL_BYTES)?;
    parse_obj(&String::from_utf8_lossy(&text), path, mode)
}

/// The materials of an OBJ's MTL files, by name, as they are named.
#[derive(Default)]
pub struct Materials {
    index: HashMap<String, u32>,
    materials: Vec<MaterialDesc>,
    /// Per material, its specular statements, which make its `brdf` once
    /// its MTL file is read.
    specular: Vec<MtlSpecular>,
    /// The images `map_Kd`, `map_Ke` and `map_d` name, each once.
    images: Vec<ImageSource>,
    /// What was read but not understood, each naming its file and line.
    warnings: Vec<String>,
}

/// The statements of OBJ or MTL text, each with the number of the line it
/// starts on: a line ending in `\` continues on the next (the OBJ spec),
/// joined as one line; a comment, from `#` to the statement's end, is not
/// part of it. A UTF-8 byte-order mark (some Windows exporters write one)
/// is not part of the first statement.
fn statements(text: &str) -> impl Iterator<Item = (usize, Cow<'_, str>)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = super::text_lines(text).enumerate();
    std::iter::from_fn(move || {
        let (index, first) = lines.next()?;
        let mut statement = Cow::Borrowed(first);
        while let Some(head) = statement.trim_end().strip_suffix('\\') {
            let head = head.to_string();
            let Some((_, next)) = lines.next() else {
                statement = Cow::Owned(head);
                break;
            };
            statement = Cow::Owned(format!("{head} {next}"));
        }
        let end = statement.find('#').unwrap_or(statement.len());
        let statement = match statement {
            Cow::Borrowed(whole) => Cow::Borrowed(&whole[..end]),
            Cow::Owned(mut whole) => {
                whole.truncate(end);
                Cow::Owned(whole)
            }
        };
        Some((index + 1, statement))
    })
}

/// The error at `line` of `path`, saying `message`.
fn line_error(path: &Path, line: usize) -> impl Fn(String) -> Error + Copy + '_ {
    move |message| Error::Line {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// Reads `mtl` (relative to the OBJ's folder) into `materials`: `newmtl
/// NAME` and its colours, alpha and images (`parse_mtl`); everything else
/// is ignored. A file that cannot be read (missing, not a regular file, too
/// large) is a warning; a malformed value an error at its line.
fn load_mtl(mtl: &Path, materials: &mut Materials) -> Result<()> {
    let bytes = match crate::files::read_capped(mtl, crate::files::MAX_TEXT_BYTES) {
        Ok(b) => b,
        // Missing, a FIFO, a device, too large: the faces can still render.
        Err(e) => {
            let reason = match e {
                Error::Io { source, .. } => source.to_string(),
                e => e.to_string(),
            };
            materials.warnings.push(format!(
                "{}: material library not read ({reason}); its faces get the default albedo",
                mtl.display()
            ));
            return Ok(());
        }
    };
    parse_mtl(&String::from_utf8_lossy(&bytes), mtl, materials)
}

/// Parses MTL text into `materials` (`load_mtl`'s rules); `mtl` names it
/// in errors. `Kd` (base colour) and `Ke` (emission) as `mtl_colour`
/// reads them; `d` (alpha) in [0, 1], below 1 a blend
/// (rendered as a mask at 0.5, with a warning); `Tr` skipped with a
/// warning; `map_Kd`, `map_Ke`, `map_d`
/// (its image's alpha: a blend too) as `texture_use` reads them.
pub fn parse_mtl(text: &str, mtl: &Path, materials: &mut Materials) -> Result<()> {
    let mut current: Option<u32> = None;
    let first = materials.materials.len();
    for (line_number, line) in statements(text) {
        let fail = line_error(mtl, line_number);
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("newmtl") => {
                let name = tokens
                    .next()
                    .ok_or_else(|| fail("newmtl needs a material name".into()))?;
                let id = materials.materials.len() as u32;
                materials.materials.push(MaterialDesc {
                    base_color: [0.8, 0.8, 0.8, 1.0],
                    name: name.to_string(),
                    ..MaterialDesc::default()
                });
                materials.specular.push(MtlSpecular::default());
                // A later definition of a name wins, as in most readers.
                materials.index.insert(name.to_string(), id);
                current = Some(id);
            }
            // Exporters disagree on what Tr means (MeshLab writes `Tr 1` for
            // opaque, others 1 − d): skipped, as Blender skips it.
            Some("Tr") => materials.warnings.push(format!(
                "{}:{line_number}: Tr is skipped (tools disagree whether it is transparency or \
                 opacity; d is read)",
                mtl.display()
            )),
            Some(keyword @ ("Ks" | "Ns" | "Pr" | "Pm")) => {
                let id = current.ok_or_else(|| fail(format!("{keyword} before any newmtl")))?;
                let at = format!("{}:{line_number}", mtl.display());
                let rest: Vec<&str> = tokens.collect();
                let specular = &mut materials.specular[id as usize];
                if keyword == "Ks" {
                    if let Some(rgb) =
                        mtl_colour(keyword, &rest, &at, &mut materials.warnings).map_err(fail)?
                    {
                        specular.ks = Some(rgb);
                    }
                    continue;
                }
                let value = rest
                    .first()
                    .and_then(|t| t.parse::<f32>().ok())
                    .filter(|x| x.is_finite() && *x >= 0.0 && (keyword == "Ns" || *x <= 1.0))
                    .ok_or_else(|| {
                        let range = if keyword == "Ns" {
                            "≥ 0"
                        } else {
                            "in [0, 1]"
                        };
                        fail(format!("{keyword} needs a number {range}"))
                    })?;
                match keyword {
                    "Ns" => specular.ns = Some(value),
                    "Pr" => specular.pr = Some(value),
                    _ => specular.pm = Some(value),
                }
            }
            Some(keyword @ ("Kd" | "Ke" | "d" | "map_Kd" | "map_Ke" | "map_d")) => {
                let id = current.ok_or_else(|| fail(format!("{keyword} before any newmtl")))?;
                let at = format!("{}:{line_number}", mtl.display());
                let rest: Vec<&str> = tokens.collect();
                let texture = if keyword.starts_with("map_") {
                    texture_use(&rest, after_words(&line, 1), mtl, &at, materials)
                } else {
                    None
                };
                let colour = match keyword {
                    "Kd" | "Ke" => {
                        match mtl_colour(keyword, &rest, &at, &mut materials.warnings)
                            .map_err(fail)?
                        {
                            Some(rgb) => Some(rgb),
                            None => continue,
                        }
                    }
                    _ => None,
                };
                let material = &mut materials.materials[id as usize];
                match (keyword, colour) {
                    ("Kd", Some(rgb)) => material.base_color[..3].copy_from_slice(&rgb),
                    ("Ke", Some(rgb)) => material.emissive = rgb,
                    ("d", _) => {
                        // `d -halo f`: the halo is not modelled; f is.
                        let value = rest
                            .iter()
                            .find(|t| **t != "-halo")
                            .ok_or_else(|| fail(format!("{keyword} needs a number")))?;
                        let x: f32 = value
                            .parse()
                            .ok()
                            .filter(|x: &f32| (0.0..=1.0).contains(x))
                            .ok_or_else(|| {
                                fail(format!("{keyword}: '{value}' is not a number in [0, 1]"))
                            })?;
                        material.base_color[3] = x;
                    }
                    ("map_Kd", _) => material.base_color_texture = texture,
                    ("map_Ke", _) => material.emissive_texture = texture,
                    _ => material.alpha_texture = texture,
                }
                let material = &mut materials.materials[id as usize];
                let blend = material.base_color[3] < 1.0 || material.alpha_texture.is_some();
                material.alpha_mode = if blend {
                    AlphaMode::Blend
                } else {
                    AlphaMode::Opaque
                };
            }
            _ => {}
        }
    }
    for (material, specular) in materials.materials[first..]
        .iter_mut()
        .zip(&materials.specular[first..])
    {
        material.brdf = specular.brdf();
        if material.alpha_mode == AlphaMode::Blend {
            materials.warnings.push(format!(
                "{}: material {}: its transparency (d < 1 or map_d) is rendered as an alpha \
                 mask with cut-off 0.5 (lambert has no partial transparency)",
                mtl.display(),
                material.name
            ));
        }
    }
    Ok(())
}

/// `Kd`/`Ke`: `r [g b]` linear RGB (g and b repeat r if omitted, as the
/// spec says), `xyz X [Y Z]` CIE XYZ; `spectral` is a warning (None).
fn mtl_colour(
    keyword: &str,
    tokens: &[&str],
    at: &str,
    warnings: &mut Vec<String>,
) -> Result<Option<[f32; 3]>, String> {
    let (space, values) = match tokens.first() {
        Some(&s @ ("xyz" | "spectral")) => (Some(s), &tokens[1..]),
        _ => (None, tokens),
    };
    if space == Some("spectral") {
        warnings.push(format!(
            "{at}: {keyword} spectral is not supported; the material keeps its default"
        ));
        return Ok(None);
    }
    let c = parse_colour(keyword, values.iter().copied())?;
    if space != Some("xyz") {
        return Ok(Some(c.map(|c| c as f32)));
    }
    let (rgb, clamped) = xyz_to_linear_srgb(c);
    if clamped {
        warnings.push(format!(
            "{at}: {keyword} xyz {c:?} lies outside sRGB; its negative components are clamped to 0"
        ));
    }
    Ok(Some(rgb))
}

/// A `map_` statement's image and its `-o`/`-s`/`-clamp` options (other
/// options skipped with a warning): None, with a warning, where the image
/// is not a file; the material then keeps its factor. `tokens` are the
/// statement's words after its keyword, `text` the same as written: the
/// image is the rest of it after the options, spaces and all, as Blender
/// reads it.
fn texture_use(
    tokens: &[&str],
    text: &str,
    mtl: &Path,
    at: &str,
    materials: &mut Materials,
) -> Option<TextureUse> {
    // Arguments each option takes: at most (numbers, -o/-s/-t 1 to 3).
    let arguments = |option: &str| match option {
        "-o" | "-s" | "-t" => 3,
        "-mm" => 2,
        _ => 1,
    };
    let (mut offset, mut scale) = ([0.0f32; 2], [1.0f32; 2]);
    let mut wrap = Wrap::Repeat;
    let mut skipped = Vec::new();
    let mut i = 0;
    while i < tokens.len() && tokens[i].starts_with('-') {
        let option = tokens[i];
        i += 1;
        if option == "-clamp" {
            // `-clamp on`: coordinates outside [0, 1] read the edge.
            match tokens.get(i) {
                Some(&"on") => wrap = Wrap::ClampToEdge,
                Some(&"off") => wrap = Wrap::Repeat,
                _ => {
                    skipped.push(option);
                    continue;
                }
            }
            i += 1;
            continue;
        }
        let mut values = Vec::new();
        while values.len() < arguments(option) && i < tokens.len() {
            match tokens[i].parse::<f32>() {
                Ok(x) if x.is_finite() => values.push(x),
                // -o/-s/-t take 1 to 3 numbers; a word ends them.
                _ if matches!(option, "-o" | "-s" | "-t") => break,
                _ => values.push(f32::NAN),
            }
            i += 1;
        }
        match option {
            "-o" if !values.is_empty() => offset = [values[0], *values.get(1).unwrap_or(&0.0)],
            "-s" if !values.is_empty() => scale = [values[0], *values.get(1).unwrap_or(&1.0)],
            _ => skipped.push(option),
        }
    }
    if !skipped.is_empty() {
        materials.warnings.push(format!(
            "{at}: texture options {} skipped (lambert reads -o, -s and -clamp on|off)",
            skipped.join(" ")
        ));
    }
    let name = after_words(text, i);
    let file = image_file(mtl, name)
        .map_err(|why| {
            materials.warnings.push(format!(
                "{at}: image '{name}' {why}; the material keeps its colour"
            ))
        })
        .ok()?;
    let source = ImageSource::File(file);
    let image = match materials.images.iter().position(|s| *s == source) {
        Some(i) => i,
        None => {
            materials.images.push(source);
            materials.images.len() - 1
        }
    } as u32;
    // -o/-s act on OBJ coordinates (v up); stored ones are (u, 1 − v), so
    // v' = s·v + o becomes 1 − v' = s·(1 − v) + (1 − s − o).
    Some(TextureUse {
        image,
        sampler: Sampler {
            wrap_u: wrap,
            wrap_v: wrap,
            ..Sampler::default()
        },
        transform: [
            [scale[0], 0.0, offset[0]],
            [0.0, scale[1], 1.0 - scale[1] - offset[1]],
        ],
    })
}

/// The file an MTL's image `name` is, relative to the MTL's folder: as
/// written, else with its backslashes as folder separators (MeshLab and
/// Blender on Windows write `textures\\grid.png`); or what it is instead
/// ("is not found (PATH)").
fn image_file(mtl: &Path, name: &str) -> Result<PathBuf, String> {
    let folder = mtl.parent().unwrap_or(Path::new("."));
    if name.is_empty() {
        return Err("is missing (no file name)".into());
    }
    let written = folder.join(name);
    let Some(why) = crate::files::not_regular(&written) else {
        return Ok(written);
    };
    if name.contains('\\') {
        let slashed = folder.join(name.replace('\\', "/"));
        return match crate::files::not_regular(&slashed) {
            None => Ok(slashed),
            Some(why) => Err(format!(
                "is {why} ({}, read with / for \\: {})",
                written.display(),
                slashed.display()
            )),
        };
    }
    Err(format!("is {why} ({})", written.display()))
}

/// `text` after its first `n` words, as written (inner runs of spaces
/// kept), without the blanks around it.
fn after_words(text: &str, n: usize) -> &str {
    let mut rest = text.trim_start();
    for _ in 0..n {
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        rest = rest[end..].trim_start();
    }
    rest.trim_end()
}

/// `r [g b]`: one number repeated, or three; each finite and non-negative.
fn parse_colour<'a>(
    keyword: &str,
    tokens: impl Iterator<Item = &'a str>,
) -> Result<[f64; 3], String> {
    let mut values = Vec::with_capacity(3);
    for token in tokens.take(3) {
        let v: f64 = token
            .parse()
            .map_err(|_| format!("{keyword}: '{token}' is not a number"))?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!(
                "{keyword}: {token} must be finite and non-negative"
            ));
        }
        values.push(v);
    }
    match values[..] {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => Err(format!(
            "{keyword} needs 1 or 3 numbers (r [g b]), found {}",
            values.len()
        )),
    }
}

/// CIE XYZ to linear sRGB (IEC 61966-2-1's D65 matrix), negative
/// components clamped to 0; whether that clamped a colour outside sRGB's
/// gamut.
fn xyz_to_linear_srgb([x, y, z]: [f64; 3]) -> ([f32; 3], bool) {
    let rgb = [
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    ];
    // The matrix's seven digits leave a primary's other components a few
    // 1e-8 from 0: rounding, not a colour outside the gamut.
    let rounding = 1e-5 * rgb.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let clamped = rgb.iter().any(|&c| c < -rounding);
    (rgb.map(|c| c.max(0.0) as f32), clamped)
}

/// The MTL files an `mtllib` statement names, relative to the OBJ's folder.
fn mtl_paths<'a>(obj: &Path, tokens: impl Iterator<Item = &'a str>) -> Vec<PathBuf> {
    let folder = obj.parent().unwrap_or(Path::new("."));
    tokens.map(|t| folder.join(t)).collect()
}

/// A face corner: position index, texture coordinate index if given, and
/// normal index if given (None inside where it names a `vt` while there is
/// none, or a normal that is not defined).
type Corner = (u32, Option<Option<u32>>, Option<Option<u32>>);

/// Faces of one kind skipped or changed: how many, and the first's line.
#[derive(Default)]
struct Skipped {
    count: usize,
    first_line: usize,
}

impl Skipped {
    fn add(&mut self, line: usize) {
        if self.count == 0 {
            self.first_line = line;
        }
        self.count += 1;
    }

    /// One warning for vertices whose colours are not finite and
    /// non-negative.
    fn warn_vertices(&self, path: &Path, warnings: &mut Vec<String>) {
        if self.count > 0 {
            warnings.push(format!(
                "{}:{}: {} vertex colours not finite and non-negative, read as white (the \
                 first on this line)",
                path.display(),
                self.first_line,
                self.count
            ));
        }
    }

    /// One warning for the kind, `what` saying what the faces were.
    fn warn(&self, path: &Path, what: &str, warnings: &mut Vec<String>) {
        if self.count > 0 {
            let faces = if self.count == 1 { "face" } else { "faces" };
            warnings.push(format!(
                "{}:{}: {} {faces} {what} (the first on this line)",
                path.display(),
                self.first_line,
                self.count
            ));
        }
    }
}

/// Parses OBJ text; `path` names it in errors and anchors its `mtllib`s.
pub fn parse_obj(text: &str, path: &Path, mode: NormalMode) -> Result<Mesh> {
    let mut mesh = Mesh::default();
    let mut materials = Materials::default();
    let mut uses_materials = false;
    let mut current: Option<u32> = None;
    let mut unknown: Vec<String> = Vec::new();
    let mut vertex_normals: Vec<DVec3> = Vec::new();
    let mut corner_normals: Vec<[Option<u32>; 3]> = Vec::new();
    let mut corners: Vec<Corner> = Vec::new();
    // `vt` (stored as (u, 1 − v)), each face corner's, and `v x y z r g b`.
    let mut texture_coordinates: Vec<[f32; 2]> = Vec::new();
    let mut corner_uvs: Vec<[[f32; 2]; 3]> = Vec::new();
    let mut vertex_colors: Vec<[f32; 4]> = Vec::new();
    let mut bad_colors = Skipped::default();
    let mut short_faces = Skipped::default();
    let mut unknown_normals = Skipped::default();
    let mut unknown_uvs = Skipped::default();
    for (line_number, line) in statements(text) {
        let fail = line_error(path, line_number);
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => {
                mesh.positions
                    .push(parse_vector(&mut tokens).map_err(fail)?);
                let rest: Vec<&str> = tokens.collect();
                // `v x y z r g b`: a colour, linear as given (`v x y z w`
                // has a weight, which a renderer ignores).
                if rest.len() == 3 {
                    let mut c = [1.0f32; 4];
                    for (k, token) in rest.iter().enumerate() {
                        c[k] = token.parse().map_err(|_| {
                            fail(format!("vertex colour: '{token}' is not a number"))
                        })?;
                    }
                    if !c.iter().all(|x| x.is_finite() && *x >= 0.0) {
                        bad_colors.add(line_number);
                        c = [1.0; 4];
                    }
                    vertex_colors.resize(mesh.positions.len() - 1, [1.0; 4]);
                    vertex_colors.push(c);
                }
            }
            Some("vt") => {
                let mut uv = [0.0f32; 2];
                for (k, slot) in uv.iter_mut().enumerate() {
                    match tokens.next() {
                        Some(token) => {
                            let x: f32 = token
                                .parse()
                                .ok()
                                .filter(|x: &f32| x.is_finite())
                                .ok_or_else(|| {
                                    fail(format!("vt: '{token}' is not a finite number"))
                                })?;
                            *slot = x;
                        }
                        None if k == 0 => return Err(fail("vt needs u [v [w]]".into())),
                        None => {}
                    }
                }
                texture_coordinates.push([uv[0], 1.0 - uv[1]]);
            }
            Some("vn") => vertex_normals.push(parse_vector(&mut tokens).map_err(fail)?),
            Some("mtllib") => {
                for mtl in mtl_paths(path, tokens) {
                    load_mtl(&mtl, &mut materials)?;
                    mesh.files.push(mtl);
                }
            }
            Some("usemtl") => {
                uses_materials = true;
                let name = tokens.next().unwrap_or("");
                current = materials.index.get(name).copied();
                if current.is_none() && !unknown.iter().any(|n| n == name) {
                    unknown.push(name.to_string());
                    mesh.warnings.push(format!(
                        "{}:{line_number}: unknown material '{name}'; its faces get the default albedo",
                        path.display()
                    ));
                }
            }
            Some("f") => {
                corners.clear();
                for token in tokens {
                    corners.push(
                        parse_corner(
                            token,
                            mesh.positions.len(),
                            texture_coordinates.len(),
                            vertex_normals.len(),
                        )
                        .map_err(fail)?,
                    );
                }
                if corners.len() < 3 {
                    short_faces.add(line_number);
                    continue;
                }
                if corners.iter().any(|c| c.2 == Some(None)) {
                    unknown_normals.add(line_number);
                    corners.iter_mut().for_each(|c| c.2 = None);
                }
                if corners.iter().any(|c| c.1 == Some(None)) {
                    unknown_uvs.add(line_number);
                    corners.iter_mut().for_each(|c| c.1 = None);
                }
                // A face's texture coordinates count where every corner
                // has one; else its corners read (0, 0).
                let textured = corners.iter().all(|c| c.1.is_some());
                for k in 1..corners.len() - 1 {
                    let fan = [corners[0], corners[k], corners[k + 1]];
                    mesh.triangles.push(fan.map(|c| c.0));
                    corner_normals.push(fan.map(|c| c.2.flatten()));
                    if textured {
                        corner_uvs.resize(mesh.triangles.len() - 1, [[0.0; 2]; 3]);
                        corner_uvs.push(
                            fan.map(|c| texture_coordinates[c.1.flatten().unwrap() as usize]),
                        );
                    }
                    mesh.face_materials.push(current);
                }
            }
            // Counted for the message of a file without triangles.
            Some("l" | "p") => mesh.skipped_lines += 1,
            // Names, groups, texture coordinates: nothing a Lambertian
            // triangle renderer uses.
            _ => {}
        }
    }
    mesh.warnings.append(&mut materials.warnings);
    short_faces.warn(
        path,
        "with fewer than 3 vertices skipped",
        &mut mesh.warnings,
    );
    unknown_normals.warn(
        path,
        "naming normals that are not defined (no such vn): those normals are dropped and \
         computed ones used",
        &mut mesh.warnings,
    );
    unknown_uvs.warn(
        path,
        "naming texture coordinates where the file has no vt before them: those are dropped and \
         the faces read (0, 0)",
        &mut mesh.warnings,
    );
    if mode == NormalMode::Smooth {
        mesh.file_normals = !corner_normals.is_empty()
            && corner_normals.iter().all(|c| c.iter().all(Option::is_some));
        mesh.normals = Some(smooth_normals(&mesh, &vertex_normals, &corner_normals));
    }
    bad_colors.warn_vertices(path, &mut mesh.warnings);
    if !corner_uvs.is_empty() {
        corner_uvs.resize(mesh.triangles.len(), [[0.0; 2]; 3]);
        mesh.uvs = Some(corner_uvs);
    }
    if !vertex_colors.is_empty() {
        vertex_colors.resize(mesh.positions.len(), [1.0; 4]);
        mesh.colors = Some(corner_values(&mesh.triangles, &vertex_colors));
    }
    if uses_materials {
        mesh.materials = materials.materials;
        mesh.images = materials.images;
    } else if mesh.colors.is_some() {
        // Colours as given: a white material rather than the default grey.
        mesh.materials = vec![MaterialDesc::default()];
        mesh.face_materials = vec![Some(0); mesh.triangles.len()];
    } else {
        mesh.face_materials.clear();
    }
    Ok(mesh)
}

fn parse_vector<'a>(tokens: &mut impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut v = [0.0; 3];
    for (i, slot) in v.iter_mut().enumerate() {
        let token = tokens
            .next()
            .ok_or_else(|| format!("expected 3 coordinates, found {i}"))?;
        let x: f64 = token
            .parse()
            .map_err(|_| format!("'{token}' is not a number"))?;
        *slot = check_coordinate(x, token)?;
    }
    Ok(DVec3::from(v))
}

/// `i`, `i/t`, `i//n` or `i/t/n`, with 1-based or negative (relative) indices.
fn parse_corner(
    token: &str,
    positions: usize,
    texture_coordinates: usize,
    normals: usize,
) -> Result<Corner, String> {
    let mut parts = token.split('/');
    let i = parse_index(parts.next().unwrap_or(""), "vertex")?;
    let position = resolve_index(i, positions).ok_or_else(|| {
        let defined = if positions == 1 { "vertex" } else { "vertices" };
        format!("vertex index {i} is out of range: {positions} {defined} defined before this line")
    })?;
    let texture = match parts.next() {
        Some(t) if !t.is_empty() => Some(parse_index(t, "texture coordinate")?),
        _ => None,
    };
    // A normal index past the normals is a quirk, not broken geometry:
    // the face is shaded with computed normals instead.
    let normal = match parts.next() {
        Some(n) if !n.is_empty() => Some(resolve_index(parse_index(n, "normal")?, normals)),
        _ => None,
    };
    // Checked after the normal parses, so a malformed corner names its
    // first malformed part. With no `vt` at all the index is an exporter's
    // quirk (trimesh reads such files), dropped as a missing normal is.
    let texture = match texture {
        Some(_) if texture_coordinates == 0 => Some(None),
        Some(t) => {
            let index = resolve_index(t, texture_coordinates).ok_or_else(|| {
                format!(
                    "texture coordinate index {t} is out of range: {texture_coordinates} vt \
                     defined before this line"
                )
            })?;
            Some(Some(index))
        }
        None => None,
    };
    Ok((position, texture, normal))
}

/// `what`: the element's name.
fn parse_index(token: &str, what: &str) -> Result<i64, String> {
    token
        .parse()
        .map_err(|_| format!("'{token}' is not a {what} index"))
}

/// A 1-based or negative index among `count` elements, 0-based; None
/// where there is no such element.
fn resolve_index(i: i64, count: usize) -> Option<u32> {
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    (i != 0 && resolved >= 0 && resolved < count as i64).then_some(resolved as u32)
}

fn smooth_normals(
    mesh: &Mesh,
    vertex_normals: &[DVec3],
    corner_normals: &[[Option<u32>; 3]],
) -> Vec<[DVec3; 3]> {
    let needs_computed = corner_normals.iter().any(|c| c.iter().any(Option::is_none));
    let area_weighted = if needs_computed {
        area_weighted_normals(mesh)
    } else {
        Vec::new()
    };
    mesh.triangles
        .iter()
        .zip(corner_normals)
        .map(|(tri, normals)| {
            if let [Some(a), Some(b), Some(c)] = *normals {
                [a, b, c].map(|i| vertex_normals[i as usize])
            } else {
                tri.map(|i| area_weighted[i as usize])
            }
        })
        .collect()
}
