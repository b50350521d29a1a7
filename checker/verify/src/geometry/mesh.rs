//! Collision meshes: STL (binary and ASCII, `stl_io`) and Wavefront OBJ (`tobj`, from
//! bytes, materials ignored) read into vertices and triangles, and turned into a solid.
//!
//! **A mesh stands for the convex hull of its vertices** (parry's `ConvexPolyhedron`).
//! Soundness for proving clearance: the hull contains the mesh (every point of a triangle
//! is a convex combination of its vertices), so if two hulls are disjoint, at distance d,
//! the meshes are disjoint at distance ≥ d. Cost: hulls may touch where the meshes do not
//! (a concave link's hull fills its hollow), so a contact of hulls is not a proof of a
//! collision; a caller reports it as "the convex hulls touch" and may confirm it on the
//! triangles ([`super::Solid::trimesh`]). parry's quickhull drops points within a small
//! tolerance of a face; the largest distance of any input vertex outside the hull is
//! measured and kept as the solid's `slack`, which a clearance proof subtracts.
//!
//! **Flat meshes** (all vertices on a plane or a line: a sign, a sheet) have no 3-D hull:
//! parry refuses them. Such a mesh becomes the hull of its vertices each moved by ±ε
//! (ε = [`FLAT_THICKNESS`] times the mesh's size) along x, y and z: the Minkowski sum of the flat hull with an
//! octahedron of radius ε, a superset of the mesh (so still sound for clearance) that is
//! thicker by at most ε. A mesh with no vertex at all is an error: it describes nothing,
//! and treating it as empty would let a broken file prove clearance.
//!
//! Vertex coordinates: a binary STL stores f32, converted to f64 exactly; OBJ text is
//! parsed as f64 (tobj's `use_f64`); stl_io parses ASCII STL numbers as f32, and that
//! rounding (at most √3 · 2^-24 of the largest coordinate per vertex) is added to the
//! solid's slack.

use super::shape::{Solid, Triangles};
use nalgebra::{Isometry3, Point3};
use parry3d::query::PointQuery;
use parry3d::shape::SharedShape;
use std::sync::Arc;

/// Thickness added on each side of a flat mesh, relative to the mesh's size (the diagonal
/// of its bounding box, at least 1 cm): parry's quickhull takes a point set whose
/// covariance has an eigenvalue below 1e-7 (after scaling to a unit box) for flat, so the
/// thickening must be well above √(3e-7) ≈ 5.5e-4 of the size. Flat collision meshes are
/// rare (none among the robots of the data); 3 mm for a 1 m sheet is the price.
pub const FLAT_THICKNESS: f64 = 3e-3;

/// The vertices and triangles of a mesh file.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub vertices: Vec<Point3<f64>>,
    pub triangles: Vec<[u32; 3]>,
    /// How far parsing may have moved a vertex from the number written in the file
    /// (metres; 0 when the file's numbers are read exactly). Added to the hull's slack.
    pub rounding: f64,
}

/// Why a mesh cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshError {
    /// A format mochi does not read (DAE, PLY, ...): the extension.
    Unsupported(String),
    /// The file is not a well-formed mesh of its format.
    Malformed(String),
    /// It holds no vertex.
    Empty,
}

impl std::fmt::Display for MeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MeshError::Unsupported(ext) if ext.eq_ignore_ascii_case("dae") => write!(
                f,
                "COLLADA (.dae) collision meshes are not supported (mochi reads STL and OBJ for collision geometry)"
            ),
            MeshError::Unsupported(ext) => write!(f, "mesh format `.{ext}` is not supported (mochi reads STL and OBJ)"),
            MeshError::Malformed(m) => write!(f, "the mesh cannot be read: {m}"),
            MeshError::Empty => write!(f, "the mesh has no vertex"),
        }
    }
}

/// The format of a mesh file, from its name's extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Stl,
    Obj,
}

/// The format named by `file_name`'s extension.
pub fn format_of(file_name: &str) -> Result<Format, MeshError> {
    let ext = file_name.rsplit_once('.').map(|(_, e)| e).unwrap_or("");
    match ext.to_ascii_lowercase().as_str() {
        "stl" => Ok(Format::Stl),
        "obj" => Ok(Format::Obj),
        _ => Err(MeshError::Unsupported(ext.to_string())),
    }
}

/// Reads a mesh file's bytes. Never panics on any bytes (property-tested).
pub fn parse(bytes: &[u8], format: Format) -> Result<MeshData, MeshError> {
    let data = match format {
        Format::Stl => parse_stl(bytes)?,
        Format::Obj => parse_obj(bytes)?,
    };
    if data.vertices.is_empty() {
        return Err(MeshError::Empty);
    }
    if let Some(p) = data.vertices.iter().find(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(MeshError::Malformed(format!("a vertex has a coordinate that is not a finite number: {p:?}")));
    }
    Ok(data)
}

fn parse_stl(bytes: &[u8]) -> Result<MeshData, MeshError> {
    // stl_io takes a file starting with `solid ` for ASCII, and trusts a binary STL's
    // triangle count. A file whose length matches its binary triangle count is binary
    // (some exporters start a binary header with `solid`: that header is blanked); any
    // other file must be ASCII.
    let binary = binary_size_matches(bytes);
    let mut owned;
    let input: &[u8] = if binary && bytes.starts_with(b"solid") {
        owned = bytes.to_vec();
        owned[..80].fill(0);
        &owned
    } else {
        if !binary && !bytes.starts_with(b"solid ") {
            return Err(MeshError::Malformed(
                "not an ASCII STL (`solid ...`), and its size does not match a binary STL's triangle count".into(),
            ));
        }
        bytes
    };
    let mut cursor = std::io::Cursor::new(input);
    let mesh = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| stl_io::read_stl(&mut cursor)))
        .map_err(|_| MeshError::Malformed("the STL reader failed".into()))?
        .map_err(|e| MeshError::Malformed(e.to_string()))?;
    let n = mesh.vertices.len();
    let vertices: Vec<Point3<f64>> =
        mesh.vertices.iter().map(|v| Point3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let mut triangles = Vec::with_capacity(mesh.faces.len());
    for f in &mesh.faces {
        if f.vertices.iter().any(|&i| i >= n) {
            return Err(MeshError::Malformed("a triangle names a vertex that does not exist".into()));
        }
        triangles.push(f.vertices.map(|i| i as u32));
    }
    // stl_io reads ASCII numbers as f32: each coordinate moved by at most half an f32 ulp
    // (relative 2^-24), so a vertex by at most √3 · 2^-24 · its largest coordinate.
    let rounding = if binary {
        0.0
    } else {
        let m = vertices.iter().map(|p| p.coords.amax()).fold(0.0, f64::max);
        3f64.sqrt() * m * (f32::EPSILON as f64) // f32::EPSILON = 2^-23: twice the bound
    };
    Ok(MeshData { vertices, triangles, rounding })
}

/// Whether `bytes` has the length of a binary STL with the triangle count in its header.
fn binary_size_matches(bytes: &[u8]) -> bool {
    if bytes.len() < 84 {
        return false;
    }
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    84 + 50 * count == bytes.len() as u64
}

/// `bytes` with the colours of vertex lines dropped, when some line carries them: `None`
/// when no `v` line has more than four numbers (nothing to drop). Some exporters (MeshLab,
/// ROS packages' meshes) write `v x y z r g b` on some lines and `v x y z` on others; tobj
/// then has colours for some vertices only and refuses the file, although collision
/// geometry never reads a colour. A `v` line of six or more numbers keeps its first three
/// (the position; the colour extension has no `w`); a line of four keeps them all (`w`, a
/// weight tobj divides by). Other lines are copied unchanged.
fn without_vertex_colours(bytes: &[u8]) -> Option<Vec<u8>> {
    let is_vertex = |line: &[u8]| {
        let t = line.trim_ascii_start();
        t.len() > 1 && t[0] == b'v' && t[1].is_ascii_whitespace()
    };
    let words = |line: &[u8]| line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty()).count();
    if !bytes.split(|&b| b == b'\n').any(|l| is_vertex(l) && words(l) >= 7) {
        return None;
    }
    let mut out = Vec::with_capacity(bytes.len());
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if k > 0 {
            out.push(b'\n');
        }
        if is_vertex(line) && words(line) >= 7 {
            let mut ws = line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty());
            for (i, w) in ws.by_ref().take(4).enumerate() {
                if i > 0 {
                    out.push(b' ');
                }
                out.extend_from_slice(w);
            }
        } else {
            out.extend_from_slice(line);
        }
    }
    Some(out)
}

fn parse_obj(bytes: &[u8]) -> Result<MeshData, MeshError> {
    let stripped = without_vertex_colours(bytes);
    let bytes = stripped.as_deref().unwrap_or(bytes);
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let mut reader = std::io::BufReader::new(bytes);
    let loaded = std::panic::catch_unwind(move || {
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
    })
    .map_err(|_| MeshError::Malformed("the OBJ reader failed".into()))?;
    let (models, _materials) = loaded.map_err(|e| MeshError::Malformed(e.to_string()))?;
    let mut data = MeshData::default();
    for m in models {
        let base = data.vertices.len() as u32;
        let pos = &m.mesh.positions;
        let n = pos.len() / 3;
        data.vertices.extend((0..n).map(|i| Point3::new(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2])));
        for t in m.mesh.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= n) {
                return Err(MeshError::Malformed("a face names a vertex that does not exist".into()));
            }
            data.triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    Ok(data)
}

/// The solid a mesh stands for: the convex hull of its vertices scaled by `scale` (per
/// axis, in the mesh's frame), placed at `pose` in its owner's frame. `None` only if
/// parry cannot build a hull even of the thickened vertices (not seen; callers report it
/// as an unusable mesh).
pub fn hull_solid(data: &MeshData, scale: [f64; 3], pose: Isometry3<f64>, name: String) -> Option<Solid> {
    let pts: Vec<Point3<f64>> =
        data.vertices.iter().map(|p| Point3::new(p.x * scale[0], p.y * scale[1], p.z * scale[2])).collect();
    let hull = hull_of(&pts)?;
    // The slack: how far a vertex lies outside the hull parry built.
    let poly = hull.as_convex_polyhedron()?;
    let slack = slack_of(poly, &pts);
    // Rounding of the projection itself: a relative 1e-12 of the mesh's extent.
    let extent = pts.iter().map(|p| p.coords.amax()).fold(0.0, f64::max);
    let rounding = 1e-12 * extent + data.rounding * scale.iter().fold(0.0, |m: f64, s| m.max(s.abs()));
    let slack = slack + rounding;
    // A mirror (an odd number of negative factors) turns the triangles inside out: their
    // winding is reversed so that each still faces out.
    let mirrored = scale.iter().filter(|s| **s < 0.0).count() % 2 == 1;
    let indices: Vec<[u32; 3]> =
        if mirrored { data.triangles.iter().map(|[a, b, c]| [*a, *c, *b]).collect() } else { data.triangles.clone() };
    let tri = Arc::new(Triangles { vertices: pts, indices });
    Some(Solid::with_slack(hull, pose, name, slack, Some(tri)))
}

/// The convex pieces of a markedly concave closed mesh ([`decompose`]) as parry shapes,
/// with their slack: the largest distance of a piece's point outside the hull parry built
/// for it, plus a relative 1e-12 of the mesh's size for the rounding of the clipped points.
/// `None` when the mesh is not decomposed or a piece has no hull.
pub fn pieces_of(t: &Triangles) -> Option<(Vec<SharedShape>, f64)> {
    let extent = t.vertices.iter().map(|p| p.coords.amax()).fold(0.0, f64::max);
    let mut slack: f64 = 0.0;
    let mut out = Vec::new();
    for piece in decompose(&t.vertices, &t.indices)? {
        let shape = hull_of(&piece)?;
        slack = slack.max(slack_of(shape.as_convex_polyhedron()?, &piece));
        out.push(shape);
    }
    Some((out, slack + 1e-12 * extent))
}

/// The convex hull of `pts` with volume, or of the points thickened by
/// [`FLAT_THICKNESS`] when they are flat (see the module doc).
fn hull_of(pts: &[Point3<f64>]) -> Option<SharedShape> {
    let hull = SharedShape::convex_hull(pts).filter(|h| h.as_convex_polyhedron().is_some_and(volume_ok));
    match hull {
        Some(h) => Some(h),
        None => {
            let first = *pts.first()?;
            let (lo, hi) = pts.iter().fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
            let e = FLAT_THICKNESS * (hi - lo).norm().max(0.01);
            let thick: Vec<Point3<f64>> = pts
                .iter()
                .flat_map(|p| {
                    [[e, 0.0, 0.0], [-e, 0.0, 0.0], [0.0, e, 0.0], [0.0, -e, 0.0], [0.0, 0.0, e], [0.0, 0.0, -e]]
                        .map(|d| Point3::new(p.x + d[0], p.y + d[1], p.z + d[2]))
                })
                .collect();
            SharedShape::convex_hull(&thick).filter(|h| h.as_convex_polyhedron().is_some_and(volume_ok))
        }
    }
}

/// Meshes of more triangles than this stay their convex hulls: the decomposition evaluates
/// a winding number over every triangle at each corner and face it tests.
pub const DECOMPOSE_MAX_TRIANGLES: usize = 2_000;
/// How many times a cell of the decomposition may be halved (at most 2^this pieces): a pin
/// 2 mm clear of a slot's wall needs cells about a centimetre high at the wall's foot. Only
/// for meshes of at most [`FINE_TRIANGLES`]; larger ones start 6 levels down (each winding
/// number costs every triangle).
const DECOMPOSE_DEPTH: usize = 12;
const FINE_TRIANGLES: usize = 200;

/// Convex pieces whose union contains the solid a closed mesh bounds, for a mesh markedly
/// concave (its volume at most [`CONCAVE_RATIO`] of its hull's); `None` for a mesh that is
/// not closed and consistently oriented (every directed edge once, and its reverse once,
/// after welding equal vertices), nearly convex, or larger than
/// [`DECOMPOSE_MAX_TRIANGLES`]: its hull stands for it alone.
///
/// **Why the union contains the solid** `S` (bounded by the mesh `M`). The mesh's box is
/// cut into cells (boxes); every point of `S` lies in some cell `K`, so in `S ∩ K`. For a
/// compact set, its hull is the hull of its boundary, and `∂(S ∩ K) ⊆ (M ∩ K) ∪ (S ∩ ∂K)`;
/// on a face `F` of `K` the same argument gives `(M ∩ F) ∪ (S ∩ ∂F)`, and on an edge `e`
/// the set `S ∩ e` is intervals whose ends are points of `M` or corners of `K`. So
/// `hull(S ∩ K) ⊆ hull((M ∩ K) ∪ (corners of K in S))`, and `M ∩ K` is the triangles
/// clipped to `K`, convex polygons whose vertices the clipping computes. The piece of `K`
/// is the hull of those vertices and of the corners of `K` whose winding number says
/// inside, or is not clearly outside (`|w| > 1/4`: a corner exactly on the surface is a
/// point of `M ∩ K` already). The winding number (the solid angles of the triangles,
/// summed, over 4π) is 1 inside a closed oriented mesh and 0 outside, whatever the
/// orientation's sign; its rounding is far below the 1/4 threshold except within a few
/// ulps of the surface. Each piece's hull slack (quickhull's tolerance) and a relative
/// 1e-12 of the mesh's size for the rounding of the clipped points are added to the
/// solid's slack by the caller.
///
/// A cell is halved (along its longest side) while its piece is not tight: the centroid
/// of a face of the piece's hull lies outside `S` (winding number below 1/4). That only
/// decides how fine the cells are, never what a piece holds.
pub fn decompose(pts: &[Point3<f64>], tris: &[[u32; 3]]) -> Option<Vec<Vec<Point3<f64>>>> {
    if tris.is_empty() || tris.len() > DECOMPOSE_MAX_TRIANGLES {
        return None;
    }
    // Weld equal vertices; drop triangles that repeat one.
    let mut canon: std::collections::HashMap<[u64; 3], u32> = std::collections::HashMap::new();
    let mut verts: Vec<Point3<f64>> = Vec::new();
    let mut index = Vec::with_capacity(pts.len());
    for p in pts {
        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let k = *canon.entry(key).or_insert_with(|| {
            verts.push(*p);
            (verts.len() - 1) as u32
        });
        index.push(k);
    }
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
    for t in tris {
        let f = [*index.get(t[0] as usize)?, *index.get(t[1] as usize)?, *index.get(t[2] as usize)?];
        if f[0] != f[1] && f[1] != f[2] && f[0] != f[2] {
            faces.push(f);
        }
    }
    // Closed and consistently oriented: each directed edge once, its reverse once.
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for f in &faces {
        for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    if faces.is_empty() || edges.iter().any(|(&(a, b), &n)| n != 1 || edges.get(&(b, a)) != Some(&1)) {
        return None;
    }
    let tri: Vec<[Point3<f64>; 3]> =
        faces.iter().map(|f| [verts[f[0] as usize], verts[f[1] as usize], verts[f[2] as usize]]).collect();
    // Markedly concave only: the mesh's volume against its hull's.
    let volume = tri.iter().map(|[a, b, c]| a.coords.dot(&b.coords.cross(&c.coords))).sum::<f64>().abs() / 6.0;
    let hull = SharedShape::convex_hull(&verts)?;
    let hull_volume = hull.as_convex_polyhedron().map(poly_volume)?;
    if !(volume > 0.0 && volume <= CONCAVE_RATIO * hull_volume) {
        return None;
    }
    let (lo, hi) = verts.iter().fold((verts[0], verts[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let all: Vec<usize> = (0..tri.len()).collect();
    let mut pieces = Vec::new();
    cells(&tri, &all, lo, hi, if tri.len() <= FINE_TRIANGLES { 0 } else { 6 }, &mut pieces);
    (!pieces.is_empty()).then_some(pieces)
}

/// A mesh whose volume is at most this fraction of its hull's is decomposed.
pub const CONCAVE_RATIO: f64 = 0.9;

fn poly_volume(c: &parry3d::shape::ConvexPolyhedron) -> f64 {
    let (v, i) = c.to_trimesh();
    i.iter()
        .map(|t| {
            let (a, b, c) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
            a.coords.dot(&b.coords.cross(&c.coords))
        })
        .sum::<f64>()
        .abs()
        / 6.0
}

/// The generalised winding number of the triangles about `p`: 1 (or −1) inside a closed
/// oriented mesh, 0 outside (Van Oosterom and Strackee's solid angle per triangle).
pub(crate) fn winding(tri: &[[Point3<f64>; 3]], p: &Point3<f64>) -> f64 {
    let mut sum = 0.0;
    for [a, b, c] in tri {
        let (a, b, c) = (a - p, b - p, c - p);
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let num = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + a.dot(&c) * lb + b.dot(&c) * la;
        sum += 2.0 * num.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// The triangle `t` clipped to the box `[lo, hi]`: the vertices of the convex polygon
/// `t ∩ box` (empty when they do not meet).
fn clip(t: &[Point3<f64>; 3], lo: &Point3<f64>, hi: &Point3<f64>) -> Vec<Point3<f64>> {
    let mut poly: Vec<Point3<f64>> = t.to_vec();
    for k in 0..3 {
        for (bound, keep_above) in [(lo[k], true), (hi[k], false)] {
            if poly.is_empty() {
                return poly;
            }
            let inside = |p: &Point3<f64>| if keep_above { p[k] >= bound } else { p[k] <= bound };
            let mut out = Vec::with_capacity(poly.len() + 1);
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                match (inside(&p), inside(&q)) {
                    (true, true) => out.push(q),
                    (true, false) | (false, true) => {
                        let s = (bound - p[k]) / (q[k] - p[k]);
                        let mut x = p + (q - p) * s;
                        x[k] = bound;
                        out.push(x);
                        if inside(&q) {
                            out.push(q);
                        }
                    }
                    (false, false) => {}
                }
            }
            poly = out;
        }
    }
    poly
}

/// The pieces of the cell `[lo, hi]` (see [`decompose`]): its piece, or its halves'.
fn cells(
    tri: &[[Point3<f64>; 3]],
    near: &[usize],
    lo: Point3<f64>,
    hi: Point3<f64>,
    depth: usize,
    out: &mut Vec<Vec<Point3<f64>>>,
) {
    // The triangles whose boxes meet the cell, and their parts inside it.
    let near: Vec<usize> = near
        .iter()
        .copied()
        .filter(|&i| {
            let [a, b, c] = &tri[i];
            (0..3).all(|k| a[k].min(b[k]).min(c[k]) <= hi[k] && a[k].max(b[k]).max(c[k]) >= lo[k])
        })
        .collect();
    let mut pts: Vec<Point3<f64>> = near.iter().flat_map(|&i| clip(&tri[i], &lo, &hi)).collect();
    let mut inside = 0;
    for i in 0..8 {
        let corner = Point3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        if winding(tri, &corner).abs() > 0.25 {
            pts.push(corner);
            inside += 1;
        }
    }
    if pts.is_empty() {
        return; // no point of the solid in this cell
    }
    if depth >= DECOMPOSE_DEPTH || (near.is_empty() && inside == 8) {
        out.push(pts);
        return;
    }
    // Tight: every face centroid of the piece's hull inside the solid (or on it).
    let tight = match SharedShape::convex_hull(&pts) {
        Some(h) => match h.as_convex_polyhedron() {
            Some(poly) => {
                let (v, idx) = poly.to_trimesh();
                idx.iter().all(|t| {
                    let c = Point3::from(
                        (v[t[0] as usize].coords + v[t[1] as usize].coords + v[t[2] as usize].coords) / 3.0,
                    );
                    winding(tri, &c).abs() > 0.25
                })
            }
            None => false,
        },
        None => false,
    };
    if tight {
        out.push(pts);
        return;
    }
    let ext = hi - lo;
    let k = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = lo[k] + 0.5 * (hi[k] - lo[k]);
    if !(mid > lo[k] && mid < hi[k]) {
        out.push(pts);
        return;
    }
    let (mut hi1, mut lo2) = (hi, lo);
    hi1[k] = mid;
    lo2[k] = mid;
    cells(tri, &near, lo, hi1, depth + 1, out);
    cells(tri, &near, lo2, hi, depth + 1, out);
}

/// The largest distance of a point of `pts` outside `poly` (0 if all are inside). A point
/// on the inner side of every face's plane is inside (cheap); the others, the few quickhull
/// dropped, are projected onto the hull (exact, slower).
fn slack_of(poly: &parry3d::shape::ConvexPolyhedron, pts: &[Point3<f64>]) -> f64 {
    let planes: Vec<(nalgebra::Vector3<f64>, f64)> = poly
        .faces()
        .iter()
        .filter_map(|f| {
            let v = *poly.vertices_adj_to_face().get(f.first_vertex_or_edge as usize)?;
            let q = poly.points().get(v as usize)?;
            Some((f.normal.into_inner(), f.normal.dot(&q.coords)))
        })
        .collect();
    pts.iter()
        .map(|p| {
            // Written out: nalgebra's generic dot is slow in unoptimised test builds.
            if !planes.is_empty() && planes.iter().all(|(n, d)| n.x * p.x + n.y * p.y + n.z * p.z <= *d) {
                return 0.0;
            }
            let proj = poly.project_local_point(p, true);
            if proj.is_inside {
                0.0
            } else {
                (proj.point - p).norm()
            }
        })
        .fold(0.0, f64::max)
}

/// A hull with volume: its points span 3 dimensions by a relative margin (parry may
/// return a degenerate polyhedron for nearly flat input instead of failing). Linear time:
/// the farthest point `b` from `p0`, the point `c` farthest from the line `p0 b`, then the
/// largest distance of a point from the plane `p0 b c`, relative to `|b − p0|`.
fn volume_ok(c: &parry3d::shape::ConvexPolyhedron) -> bool {
    let p = c.points();
    let Some(&a) = p.first() else { return false };
    let far = |f: &dyn Fn(&Point3<f64>) -> f64| p.iter().copied().max_by(|x, y| f(x).total_cmp(&f(y)));
    let Some(b) = far(&|k| (k - a).norm()) else { return false };
    let size = (b - a).norm();
    if size.is_nan() || size <= 0.0 {
        return false;
    }
    let u = (b - a) / size;
    let Some(c) = far(&|k| (k - a).cross(&u).norm()) else { return false };
    let n = (c - a).cross(&u);
    if n.norm().is_nan() || n.norm() <= 1e-9 * size {
        return false;
    }
    let n = n.normalize();
    p.iter().map(|k| n.dot(&(k - a)).abs()).fold(0.0, f64::max) > 1e-9 * size
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const CUBE_OBJ: &str =
        "# a unit cube\nmtllib cube.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        usemtl red\nf 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

    fn ascii_stl() -> String {
        let tri = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            format!(
                "facet normal 0 0 0\n outer loop\n  vertex {} {} {}\n  vertex {} {} {}\n  vertex {} {} {}\n endloop\nendfacet\n",
                a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]
            )
        };
        // A tetrahedron.
        let (o, x, y, z) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]);
        format!("solid t\n{}{}{}{}endsolid t\n", tri(o, y, x), tri(o, x, z), tri(o, z, y), tri(x, y, z))
    }

    fn binary_stl(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b.extend((tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend([0u8; 12]);
            for v in t {
                for c in v {
                    b.extend(c.to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    }

    #[test]
    fn obj_cube_hull_and_scale() {
        let d = parse(CUBE_OBJ.as_bytes(), Format::Obj).unwrap();
        assert_eq!(d.vertices.len(), 8);
        assert_eq!(d.triangles.len(), 12);
        assert_eq!(d.rounding, 0.0);
        let s = hull_solid(&d, [2.0, 1.0, 0.5], Isometry3::identity(), "cube".into()).unwrap();
        let a = s.local_aabb();
        assert!((a.maxs.x - 2.0).abs() < 1e-9 && (a.maxs.y - 1.0).abs() < 1e-9 && (a.maxs.z - 0.5).abs() < 1e-9);
        assert!(s.slack < 1e-9, "{}", s.slack);
        assert!((s.bounding_radius() - (4.0f64 + 1.0 + 0.25).sqrt()).abs() < 1e-9);
        assert!(s.trimesh().is_some());
        assert!(s.is_hull);
    }

    #[test]
    fn stl_ascii_and_binary() {
        let d = parse(ascii_stl().as_bytes(), Format::Stl).unwrap();
        assert_eq!((d.vertices.len(), d.triangles.len()), (4, 4));
        let b = binary_stl(&[
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        ]);
        let d = parse(&b, Format::Stl).unwrap();
        assert_eq!((d.vertices.len(), d.triangles.len()), (4, 2));
        // A binary STL whose header says more triangles than it holds.
        let mut bad = b.clone();
        bad[80] = 200;
        assert!(matches!(parse(&bad, Format::Stl), Err(MeshError::Malformed(_))));
        // A binary STL whose header starts with "solid" (some exporters write that).
        let mut s = b.clone();
        s[..5].copy_from_slice(b"solid");
        assert_eq!(parse(&s, Format::Stl).unwrap().triangles.len(), 2);
    }

    #[test]
    fn formats_and_empty_meshes() {
        assert_eq!(format_of("a/b/Link_1.STL"), Ok(Format::Stl));
        assert_eq!(format_of("x.obj"), Ok(Format::Obj));
        let e = format_of("base.dae").unwrap_err();
        assert!(e.to_string().contains("COLLADA"), "{e}");
        assert!(matches!(format_of("noext"), Err(MeshError::Unsupported(_))));
        assert_eq!(parse(b"# nothing\n", Format::Obj).unwrap_err(), MeshError::Empty);
        assert!(parse(b"v 1 2 nan\nv 0 0 0\nv 1 1 1\nf 1 2 3\n", Format::Obj).is_err());
    }

    /// The slack measures points outside a hull: the cube's hull, and points just outside
    /// each of its faces and corners (if the face planes were misread, some would count as
    /// inside and the slack would be 0).
    #[test]
    fn slack_measures_points_outside_the_hull() {
        let d = parse(CUBE_OBJ.as_bytes(), Format::Obj).unwrap();
        let h = SharedShape::convex_hull(&d.vertices).unwrap();
        let poly = h.as_convex_polyhedron().unwrap();
        assert_eq!(slack_of(poly, &d.vertices), 0.0);
        assert_eq!(slack_of(poly, &[Point3::new(0.5, 0.5, 0.5)]), 0.0);
        for p in [
            [0.5, 0.5, 1.01],
            [0.5, -0.01, 0.5],
            [1.01, 0.5, 0.5],
            [0.5, 0.5, -0.01],
            [-0.01, 0.5, 0.5],
            [0.5, 1.01, 0.5],
        ] {
            let s = slack_of(poly, &[Point3::from(p)]);
            assert!((s - 0.01).abs() < 1e-9, "{p:?}: {s}");
        }
        let s = slack_of(poly, &[Point3::new(1.01, 1.01, 1.01)]);
        assert!((s - 0.01 * 3f64.sqrt()).abs() < 1e-9, "{s}");
    }

    /// A flat mesh (one triangle) becomes a thin solid that still contains the triangle.
    #[test]
    fn flat_mesh_is_thickened_and_contains_the_triangle() {
        let d = MeshData {
            vertices: vec![Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)],
            triangles: vec![[0, 1, 2]],
            rounding: 0.0,
        };
        let s = hull_solid(&d, [1.0; 3], Isometry3::identity(), "sheet".into()).unwrap();
        let a = s.local_aabb();
        let e = FLAT_THICKNESS * 2f64.sqrt();
        assert!(a.maxs.z >= e * 0.99 && a.maxs.z < e * 1.01 && a.mins.z < -e * 0.99, "{a:?}");
        for p in [Point3::new(0.2, 0.2, 0.0), Point3::new(0.0, 0.0, 0.0), Point3::new(0.5, 0.5, 0.0)] {
            assert!(s.shape.contains_point(&s.pose, &p), "{p:?}");
        }
        // A line, and a single point, too.
        let line = MeshData {
            vertices: vec![Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0)],
            triangles: vec![],
            rounding: 0.0,
        };
        assert!(hull_solid(&line, [1.0; 3], Isometry3::identity(), "line".into()).is_some());
        let point = MeshData { vertices: vec![Point3::new(3.0, 0.0, 0.0)], triangles: vec![], rounding: 0.0 };
        let s = hull_solid(&point, [1.0; 3], Isometry3::identity(), "pt".into()).unwrap();
        assert!(s.shape.contains_point(&s.pose, &Point3::new(3.0, 0.0, 0.0)));
    }

    /// An OBJ with colours on some vertex lines only (`v x y z r g b` and `v x y z` mixed, as
    /// some exporters write): read, with the positions alone; a `w` weight still divides.
    #[test]
    fn obj_with_colours_on_some_vertices() {
        let text = "v 0 0 0 1 0 0\nv 1 0 0\nv\t0 1 0 0.5 0.5 0.5\nv 0 0 2 2\r\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";
        let d = parse(text.as_bytes(), Format::Obj).unwrap();
        assert_eq!(d.vertices.len(), 4);
        assert_eq!(d.triangles.len(), 4);
        let mut pts: Vec<[f64; 3]> = d.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(pts, vec![[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
        // Every vertex coloured: read as before.
        let all = "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nv 0 0 1 1 0 0\nf 1 2 3\nf 1 2 4\n";
        assert_eq!(parse(all.as_bytes(), Format::Obj).unwrap().vertices.len(), 4);
        // A file with no coloured line is passed through untouched.
        assert!(without_vertex_colours(CUBE_OBJ.as_bytes()).is_none());
    }

    /// The cradle (a U-shaped closed mesh): decomposed into pieces whose union holds every
    /// point of the solid (sampled on a grid, each tested by the winding number), and a box
    /// in its slot, 1 cm from the walls and the floor, is proved apart by the pieces although it
    /// lies inside the hull.
    #[test]
    fn a_concave_mesh_is_decomposed_into_pieces_that_hold_it() {
        let text = std::fs::read_to_string(crate::testing::repo("robots/meshes/cradle.obj")).unwrap();
        let d = parse(text.as_bytes(), Format::Obj).unwrap();
        let s = hull_solid(&d, [1.0; 3], Isometry3::identity(), "cradle".into()).unwrap();
        let (pieces, extra) = s.pieces().expect("the cradle is decomposed");
        assert!(pieces.len() >= 2 && extra >= 0.0, "{} pieces", pieces.len());
        let t = s.triangles.as_ref().unwrap();
        let tri: Vec<[Point3<f64>; 3]> = t
            .indices
            .iter()
            .map(|f| [t.vertices[f[0] as usize], t.vertices[f[1] as usize], t.vertices[f[2] as usize]])
            .collect();
        let mut inside = 0;
        for i in 0..=30 {
            for j in 0..=10 {
                for k in 0..=20 {
                    let p = Point3::new(-0.15 + 0.01 * i as f64, -0.1 + 0.02 * j as f64, 0.005 * k as f64);
                    if winding(&tri, &p).abs() < 0.5 {
                        continue;
                    }
                    inside += 1;
                    let held =
                        pieces.iter().any(|q| q.shape.distance_to_point(&Isometry3::identity(), &p, true) <= 1e-12);
                    assert!(held, "{p:?} of the solid is in no piece");
                }
            }
        }
        assert!(inside > 1000, "{inside}");
        // A box in the slot: the hulls overlap, the pieces are 1 cm apart from it.
        let part = Solid::mochi_box(0.08, 0.1, 0.05, Isometry3::translation(0.0, 0.0, 0.04), "part").unwrap();
        let (_, hull_lower, _) = super::super::search::bnb::parry_closest(&s.shape, &s.pose, &part.shape, &part.pose);
        assert!(hull_lower < 0.0, "{hull_lower}");
        let (_, lower, _) = super::super::solid_closest(&s, &s.pose, &part, &part.pose);
        assert!(lower > 0.0 && lower <= 0.01 + 1e-9, "{lower}");
        // Wider than the slot: no lower bound above 0.
        let wide = Solid::mochi_box(0.12, 0.1, 0.05, Isometry3::translation(0.0, 0.0, 0.04), "wide").unwrap();
        let (_, lower, _) = super::super::solid_closest(&s, &s.pose, &wide, &wide.pose);
        assert!(lower <= 0.0, "{lower}");
        // An open mesh (the cube less one face) is not decomposed.
        let open = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
        let d = parse(open.as_bytes(), Format::Obj).unwrap();
        assert!(decompose(&d.vertices, &d.triangles).is_none());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = parse(&bytes, Format::Stl);
            let _ = parse(&bytes, Format::Obj);
        }

        #[test]
        fn arbitrary_obj_text_never_panics(lines in proptest::collection::vec(
            prop_oneof![
                "v( -?[0-9]{1,3}(\\.[0-9]{1,3})?){0,4}",
                "f( -?[0-9]{1,2}(/[0-9]{0,2}){0,2}){0,5}",
                "(o|g|usemtl|mtllib|vn|vt) [a-z0-9 .]{0,8}",
            ], 0..20)) {
            let text = lines.join("\n");
            if let Ok(d) = parse(text.as_bytes(), Format::Obj) {
                let _ = hull_solid(&d, [1.0; 3], Isometry3::identity(), "x".into());
            }
        }

        #[test]
        fn arbitrary_ascii_stl_never_panics(body in "(solid|facet|normal|outer|loop|vertex|endloop|endfacet|endsolid| |\n|-?[0-9]\\.[0-9]){0,60}") {
            let _ = parse(format!("solid x\n{body}").as_bytes(), Format::Stl);
        }
    }
}
