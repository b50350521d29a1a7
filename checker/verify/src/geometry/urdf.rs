//! URDF files to kinematic trees ([`super::Robot`]), with diagnostics that point into the
//! URDF file (E0501-E0507, E0530).
//!
//! URDFs are downloaded, so the text is bounded first (`crate::xmlscan`: nesting, attributes per
//! element, namespace declarations), before any parser that is not linear in those sees it,
//! and a robot must stay within `MAX_REACH` (1e6 m) of its root (E0530) so that no pose or
//! distance overflows.
//!
//! urdf-rs parses the robot; it gives no positions, so the text is also read with
//! roxmltree, which knows the byte range of every element and attribute: a malformed
//! document gets its line from roxmltree's error, and the attributes urdf-rs would only
//! reject with a serde message (numbers in `xyz`, `rpy`, `size`, `radius`, `length`,
//! `scale`, `<limit>`, `<mimic>`) are checked here first so that the diagnostic names
//! the element and points at the attribute. The URDF text is added to the [`SourceDb`].
//!
//! Visual elements are ignored (only `<collision>` is geometry). Mesh file names resolve
//! as ROS does: `package://PKG/rest` against the nearest folder above the URDF's own that
//! holds `PKG/rest` (the package root), `file:///abs` as an absolute path, anything else
//! relative to the URDF's folder. Mesh files are read once each.
//!
//! Joint types: revolute, continuous, prismatic and fixed; floating, planar (and
//! spherical) are E0504. `<mimic>` is supported ([`super::kinematics`]).

use super::kinematics::{Joint, JointKind, Link, Mimic, Robot};
use super::mesh;
use super::shape::Solid;
use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, SourceDb, Span};
use crate::syntax::ByteLoader;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Loads the URDF at `path` (named by the mochi source at `at`) and every collision mesh
/// it names, through `read`. The URDF's text is added to `db`; diagnostics point into it
/// (or at `at` when the URDF itself cannot be read).
pub fn load_robot(
    db: &mut SourceDb,
    path: &Path,
    at: Span,
    read: &mut ByteLoader<'_>,
) -> Result<Robot, Vec<Diagnostic>> {
    let bytes = read(path).map_err(|e| {
        vec![Diagnostic::error(
            Code::GeometryFileMissing,
            at,
            format!("cannot read the URDF file `{}`: {e}", path.display()),
        )
        .with_help("check the path: it is relative to the file that names it")]
    })?;
    let (text, bad_utf8) = match String::from_utf8(bytes) {
        Ok(t) => (t, None),
        Err(e) => {
            let off = e.utf8_error().valid_up_to();
            (String::from_utf8_lossy(e.as_bytes()).into_owned(), Some(off))
        }
    };
    let file = db.add(path.display().to_string(), text.clone());
    let span = |r: Range<usize>| Span::new(file, r.start, r.end);
    // The character at `off` (an empty span at the end of the text: an empty file, or an
    // error at its end, must still point inside it).
    let char_at = |off: usize| {
        let off = off.min(text.len());
        let len = text.get(off..).and_then(|r| r.chars().next()).map_or(0, char::len_utf8);
        Span::new(file, off, off + len)
    };
    if let Some(off) = bad_utf8 {
        // `off` is where the invalid bytes start; the lossy text holds U+FFFD there.
        return Err(vec![Diagnostic::error(Code::UrdfInvalid, char_at(off), "the URDF file is not UTF-8")
            .with_help("save the URDF as UTF-8 (XML's default encoding)")]);
    }
    // Bound the document's shape before any parser sees it (see `crate::xmlscan`).
    if let Some(e) = crate::xmlscan::excess(&text) {
        let (off, msg, help) = match e {
            crate::xmlscan::Excess::Depth(off) => (
                off,
                format!("elements nest deeper than {} levels here", crate::xmlscan::MAX_NESTING),
                "a URDF nests about 6 deep (robot, link, collision, geometry, shape): remove the extra nesting",
            ),
            crate::xmlscan::Excess::Attributes(off) => (
                off,
                format!("this element has more than {} attributes", crate::xmlscan::MAX_ATTRIBUTES),
                "a URDF element has a few attributes (`<inertia>` has the most: 6): remove the extra ones",
            ),
            crate::xmlscan::Excess::Namespaces(off) => (
                off,
                format!("the URDF declares more than {} XML namespaces", crate::xmlscan::MAX_NAMESPACES),
                "a URDF declares a few namespaces (`xmlns:xacro`, Gazebo's): remove the extra declarations",
            ),
        };
        let end =
            text[off..].find(|c: char| c.is_ascii_whitespace() || c == '>' || c == '=').map_or(text.len(), |k| off + k);
        let at = if end > off { span(off..end) } else { char_at(off) };
        return Err(vec![Diagnostic::error(Code::UrdfInvalid, at, msg)
            .with_note("mochi bounds a URDF's nesting, attributes and namespaces so that reading it takes time linear in its size")
            .with_help(help)]);
    }
    let doc = match roxmltree::Document::parse(&text) {
        Ok(d) => d,
        Err(e) => {
            let off = offset_of(&text, e.pos().row, e.pos().col);
            return Err(vec![Diagnostic::error(
                Code::UrdfInvalid,
                char_at(off),
                format!("the URDF is not well-formed XML: {e}"),
            )
            .with_help("fix the XML at this position (an unclosed tag, a stray `<` or `&`, unquoted attribute)")]);
        }
    };
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(vec![Diagnostic::error(
            Code::UrdfInvalid,
            span(root.range()),
            format!("the document's root element is `<{}>`, not `<robot>`", root.tag_name().name()),
        )
        .with_help("a URDF file holds one `<robot name=...>` element")]);
    }
    let mut diags = Vec::new();
    let elems = scan(&doc, file, &mut diags);
    if !diags.is_empty() {
        return Err(diags);
    }
    let parsed = urdf_rs::read_from_string(&text).map_err(|e| {
        vec![Diagnostic::error(
            Code::UrdfInvalid,
            span(root.range()),
            format!("the URDF cannot be read as a robot: {e}"),
        )
        .with_help("check the elements against the URDF specification (wiki.ros.org/urdf/XML)")]
    })?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut meshes: HashMap<PathBuf, Result<mesh::MeshData, (Code, String)>> = HashMap::new();
    let mut links = Vec::new();
    let mut link_index = HashMap::new();
    for (li, l) in parsed.links.iter().enumerate() {
        if link_index.insert(l.name.clone(), li).is_some() {
            let at = elems.links.get(&l.name).map_or(span(root.range()), |e| span(e.range.clone()));
            diags.push(
                Diagnostic::error(Code::UrdfNotATree, at, format!("two links are named `{}`", l.name))
                    .with_help("give every link a unique name"),
            );
        }
        let mut solids = Vec::new();
        let el = elems.links.get(&l.name);
        for (ci, c) in l.collision.iter().enumerate() {
            let name = format!("{} (collision {})", l.name, ci + 1);
            let place = pose(&c.origin);
            let geo_at = el.and_then(|e| e.collisions.get(ci)).map_or(span(root.range()), |g| span(g.clone()));
            let solid = match &c.geometry {
                urdf_rs::Geometry::Box { size } => Solid::urdf_box(size.0, place, &name),
                urdf_rs::Geometry::Cylinder { radius, length } => Solid::urdf_cylinder(*radius, *length, place, &name),
                urdf_rs::Geometry::Capsule { radius, length } => Solid::urdf_capsule(*radius, *length, place, &name),
                urdf_rs::Geometry::Sphere { radius } => Solid::sphere(*radius, place, &name),
                urdf_rs::Geometry::Mesh { filename, scale } => {
                    let file_at = el.and_then(|e| e.mesh_files.get(ci)).and_then(|r| r.clone()).map_or(geo_at, span);
                    match load_mesh(filename, scale.map(|s| s.0), &dir, place, name.clone(), read, &mut meshes) {
                        Ok(s) => Ok(s),
                        Err((code, msg, help)) => {
                            diags.push(Diagnostic::error(code, file_at, msg).with_help(help));
                            continue;
                        }
                    }
                }
            };
            match solid {
                Ok(s) => solids.push(s),
                Err(e) => diags.push(
                    Diagnostic::error(
                        Code::ShapeInvalid,
                        geo_at,
                        format!("collision geometry of link `{}`: {e}", l.name),
                    )
                    .with_help("give the shape positive finite sizes (metres)"),
                ),
            }
        }
        links.push(Link { name: l.name.clone(), solids });
    }
    let mut joints = Vec::new();
    let mut joint_index = HashMap::new();
    for (ji, j) in parsed.joints.iter().enumerate() {
        if joint_index.insert(j.name.clone(), ji).is_some() {
            let at = elems.joints.get(&j.name).map_or(span(root.range()), |e| span(e.range.clone()));
            diags.push(
                Diagnostic::error(Code::UrdfNotATree, at, format!("two joints are named `{}`", j.name))
                    .with_help("give every joint a unique name"),
            );
        }
    }
    for j in &parsed.joints {
        let el = elems.joints.get(&j.name);
        let at = el.map_or(span(root.range()), |e| span(e.range.clone()));
        let kind = match j.joint_type {
            urdf_rs::JointType::Fixed => JointKind::Fixed,
            urdf_rs::JointType::Revolute => JointKind::Revolute,
            urdf_rs::JointType::Continuous => JointKind::Continuous,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            ref other => {
                let t = el.and_then(|e| e.type_attr.clone()).map_or(at, span);
                diags.push(
                    Diagnostic::error(Code::JointUnsupported, t, format!("joint `{}` is {other:?}: mochi supports revolute, continuous, prismatic and fixed joints", j.name).to_lowercase())
                        .with_help("make the joint `fixed` and place the robot's base by its participant's pose (`at:`) or by mounting it"),
                );
                continue;
            }
        };
        let link = |name: &str| link_index.get(name).copied();
        let (Some(parent), Some(child)) = (link(&j.parent.link), link(&j.child.link)) else {
            let missing = if link(&j.parent.link).is_none() { &j.parent.link } else { &j.child.link };
            diags.push(
                Diagnostic::error(
                    Code::UrdfNotATree,
                    at,
                    format!("joint `{}` names the link `{missing}`, which the URDF does not define", j.name),
                )
                .with_help("define the link, or correct the joint's `<parent link>` / `<child link>`"),
            );
            continue;
        };
        let axis = Vector3::new(j.axis.xyz.0[0], j.axis.xyz.0[1], j.axis.xyz.0[2]);
        let axis = match Unit::try_new(axis, 1e-12) {
            Some(a) => a,
            None if kind == JointKind::Fixed => Vector3::x_axis(),
            None => {
                let a = el.and_then(|e| e.axis.clone()).map_or(at, span);
                diags.push(
                    Diagnostic::error(Code::UrdfInvalid, a, format!("joint `{}` has a zero axis", j.name))
                        .with_help("give the axis a non-zero direction, e.g. `<axis xyz=\"0 0 1\"/>`"),
                );
                continue;
            }
        };
        let limits = match kind {
            JointKind::Revolute | JointKind::Prismatic => Some((j.limit.lower, j.limit.upper)),
            _ => None,
        };
        let velocity = match kind {
            JointKind::Fixed => None,
            _ => Some(j.limit.velocity).filter(|v| v.is_finite() && *v > 0.0),
        };
        let mimic = match &j.mimic {
            None => None,
            Some(m) => match joint_index.get(&m.joint) {
                Some(&master) => {
                    Some(Mimic { master, multiplier: m.multiplier.unwrap_or(1.0), offset: m.offset.unwrap_or(0.0) })
                }
                None => {
                    diags.push(
                        Diagnostic::error(
                            Code::MimicInvalid,
                            el.and_then(|e| e.mimic.clone()).map_or(at, span),
                            format!("joint `{}` mimics `{}`, which the URDF does not define", j.name, m.joint),
                        )
                        .with_help("name a movable joint of the same URDF in `<mimic joint=...>`"),
                    );
                    continue;
                }
            },
        };
        joints.push(Joint {
            name: j.name.clone(),
            kind,
            parent,
            child,
            origin: pose(&j.origin),
            axis,
            limits,
            velocity,
            mimic,
        });
    }
    if !diags.is_empty() {
        return Err(diags);
    }
    // Mimic masters index parsed.joints; every joint was pushed (no error), so they agree.
    let robot = Robot::new(parsed.name.clone(), links, joints).map_err(|e| {
        let at = match (e.joint, e.link) {
            (Some(j), _) => parsed.joints.get(j).and_then(|j| elems.joints.get(&j.name)).map(|e| e.range.clone()),
            (None, Some(l)) => parsed.links.get(l).and_then(|l| elems.links.get(&l.name)).map(|e| e.range.clone()),
            _ => None,
        };
        let code = if e.message.contains("mimic") { Code::MimicInvalid } else { Code::UrdfNotATree };
        vec![Diagnostic::error(code, span(at.unwrap_or(root.range())), e.message)
            .with_help("a URDF is one tree: one root link, every other link the child of exactly one joint")]
    })?;
    // The robot's size: finite, and small enough that no pose or distance overflows. The
    // reach only grows down a chain, so the link to blame is one whose parent is within.
    // The file's own numbers: a slider whose limits are no range is not too large for
    // them (how far it slides is the contracts' business; `Robot::reach` says unbounded).
    let reach = robot.written_reach();
    let over = |r: f64| !within_reach(r);
    let blame = (0..robot.links.len())
        .find(|&l| over(reach[l].1) && robot.parent_joint(l).is_none_or(|j| !over(reach[robot.joints[j].parent].0)));
    if let Some(l) = blame {
        let (frame, solids) = reach[l];
        let link = &robot.links[l];
        let (at, msg) = match robot.parent_joint(l) {
            Some(j) if over(frame) => {
                let name = &robot.joints[j].name;
                let e = elems.joints.get(name);
                let at = e.and_then(|e| e.origin.clone()).or_else(|| e.map(|e| e.range.clone()));
                (at, format!("joint `{name}` places link `{}` {} from the root", link.name, metres(frame)))
            }
            _ => (
                elems.links.get(&link.name).map(|e| e.range.clone()),
                format!("the collision geometry of link `{}` reaches {} from the root", link.name, metres(solids)),
            ),
        };
        return Err(vec![Diagnostic::error(
            Code::UrdfTooLarge,
            span(at.unwrap_or(root.range())),
            format!("{msg}: beyond mochi's bound of {MAX_REACH:e} m"),
        )
        .with_help("check the numbers' units (metres) and magnitudes: a robot fits in a few metres")]);
    }
    Ok(robot)
}

/// How far from its root a robot may reach (metres): every pose and distance mochi computes
/// for it is then far from overflow (squares of 1e6 are 1e12).
const MAX_REACH: f64 = 1e6;

/// `r` is a number no larger than [`MAX_REACH`] (NaN is not).
fn within_reach(r: f64) -> bool {
    r.is_finite() && r <= MAX_REACH
}

fn metres(r: f64) -> String {
    if r.is_finite() {
        format!("{r:.3e} m")
    } else {
        "farther than any number".to_string()
    }
}

/// URDF's `<origin xyz rpy>`: rotation `Rz(yaw) Ry(pitch) Rx(roll)` then translation.
fn pose(p: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = p.xyz.0;
    let [r, pi, ya] = p.rpy.0;
    Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_euler_angles(r, pi, ya))
}

type MeshCache = HashMap<PathBuf, Result<mesh::MeshData, (Code, String)>>;

fn load_mesh(
    filename: &str,
    scale: Option<[f64; 3]>,
    dir: &Path,
    place: Isometry3<f64>,
    name: String,
    read: &mut ByteLoader<'_>,
    cache: &mut MeshCache,
) -> Result<Solid, (Code, String, String)> {
    let scale = scale.unwrap_or([1.0; 3]);
    // A negative factor mirrors the mesh (how URDFs make a left part of a right one); zero
    // would flatten it into less than it is.
    if scale.iter().any(|s| !(s.is_finite() && *s != 0.0)) {
        return Err((
            Code::ShapeInvalid,
            format!("mesh `{filename}` has scale {scale:?}: each factor must be a finite number other than 0"),
            "use a non-zero scale for each axis (a negative one mirrors the mesh)".into(),
        ));
    }
    let format = mesh::format_of(filename).map_err(|e| {
        (
            Code::MeshUnreadable,
            format!("collision mesh `{filename}`: {e}"),
            "convert the mesh to STL or OBJ and name that file".to_string(),
        )
    })?;
    let candidates = candidates(filename, dir);
    let mut found = None;
    let mut tried = Vec::new();
    for c in &candidates {
        if let Some(hit) = cache.get(c) {
            found = Some((c.clone(), hit.clone()));
            break;
        }
        match read(c) {
            Ok(bytes) => {
                let r = mesh::parse(&bytes, format).map_err(|e| (Code::MeshUnreadable, e.to_string()));
                cache.insert(c.clone(), r.clone());
                found = Some((c.clone(), r));
                break;
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => tried.push(c.display().to_string()),
            Err(e) => {
                return Err((
                    Code::GeometryFileMissing,
                    format!("cannot read the mesh `{}`: {e}", c.display()),
                    "name a regular mesh file of at most 64 MiB".into(),
                ))
            }
        }
    }
    let Some((at, data)) = found else {
        return Err((
            Code::GeometryFileMissing,
            format!("the mesh file `{filename}` does not exist (looked for {})", tried.join(", ")),
            "put the mesh where the URDF names it, or correct the `filename`; `package://PKG/...` is looked up in the folders above the URDF".into(),
        ));
    };
    let data = data.map_err(|(code, m)| {
        (
            code,
            format!("collision mesh `{}`: {m}", at.display()),
            "convert the mesh to a valid STL or OBJ file".to_string(),
        )
    })?;
    // The scaled vertices must be finite and within the robot's bound before a hull is
    // built of them (their products may overflow though each factor is finite).
    let far =
        data.vertices.iter().flat_map(|p| (0..3).map(move |i| (p[i] * scale[i]).abs())).find(|&c| !within_reach(c));
    if let Some(c) = far {
        return Err((
            Code::UrdfTooLarge,
            format!(
                "collision mesh `{}` scaled by {scale:?} has a vertex {} from its origin: beyond mochi's bound of {MAX_REACH:e} m",
                at.display(),
                metres(c)
            ),
            "check the mesh's units and the `scale` (a mesh in millimetres takes `scale=\"0.001 0.001 0.001\"`)".to_string(),
        ));
    }
    mesh::hull_solid(&data, scale, place, name).ok_or_else(|| {
        (
            Code::MeshUnreadable,
            format!("no convex hull can be built of the mesh `{}`", at.display()),
            "check the mesh's vertices".to_string(),
        )
    })
}

/// Where a URDF mesh name may be, in the order to try.
fn candidates(filename: &str, dir: &Path) -> Vec<PathBuf> {
    if let Some(rest) = filename.strip_prefix("package://") {
        // Every ancestor of the URDF's folder, nearest first, as a package root.
        return dir.ancestors().map(|a| a.join(rest)).collect();
    }
    if let Some(abs) = filename.strip_prefix("file://") {
        return vec![PathBuf::from(abs)];
    }
    vec![dir.join(filename)]
}

/// An attribute value for a message: in backquotes, cut short after 60 characters (a
/// hostile file may hold megabytes in one attribute), with how many numbers it holds.
fn quoted(value: &str, numbers: usize) -> String {
    const SHOWN: usize = 60;
    match value.char_indices().nth(SHOWN) {
        None => format!("`{value}`"),
        Some((cut, _)) => format!("`{}...` ({numbers} values, {} bytes)", &value[..cut], value.len()),
    }
}

/// The byte offset of 1-based `row`, `col` (characters) in `text`.
fn offset_of(text: &str, row: u32, col: u32) -> usize {
    let mut off = 0;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        if i + 1 == row as usize {
            return off + line.char_indices().nth(col.saturating_sub(1) as usize).map_or(line.len(), |(b, _)| b);
        }
        off += line.len();
    }
    text.len()
}

/// Positions of the elements of one link.
#[derive(Default)]
struct LinkElems {
    range: Range<usize>,
    /// Per `<collision>`: its `<geometry>`'s range.
    collisions: Vec<Range<usize>>,
    /// Per `<collision>`: its `<mesh filename>` value's range, if a mesh.
    mesh_files: Vec<Option<Range<usize>>>,
}

#[derive(Default)]
struct JointElems {
    range: Range<usize>,
    type_attr: Option<Range<usize>>,
    origin: Option<Range<usize>>,
    axis: Option<Range<usize>>,
    mimic: Option<Range<usize>>,
}

#[derive(Default)]
struct Elems {
    links: HashMap<String, LinkElems>,
    joints: HashMap<String, JointElems>,
}

/// Numeric attributes: (element, attribute, how many numbers).
const NUMERIC: &[(&str, &str, usize)] = &[
    ("origin", "xyz", 3),
    ("origin", "rpy", 3),
    ("axis", "xyz", 3),
    ("box", "size", 3),
    ("cylinder", "radius", 1),
    ("cylinder", "length", 1),
    ("capsule", "radius", 1),
    ("capsule", "length", 1),
    ("sphere", "radius", 1),
    ("mesh", "scale", 3),
    ("limit", "lower", 1),
    ("limit", "upper", 1),
    ("limit", "velocity", 1),
    ("mimic", "multiplier", 1),
    ("mimic", "offset", 1),
];

/// Collects element positions and checks names and numeric attributes of links and joints.
fn scan(doc: &roxmltree::Document<'_>, file: FileId, diags: &mut Vec<Diagnostic>) -> Elems {
    let span = |r: Range<usize>| Span::new(file, r.start, r.end);
    let mut out = Elems::default();
    let root = doc.root_element();
    for item in root.children().filter(|n| n.is_element()) {
        let tag = item.tag_name().name();
        if tag != "link" && tag != "joint" {
            continue;
        }
        let Some(name) = item.attribute("name") else {
            diags.push(
                Diagnostic::error(Code::UrdfInvalid, span(item.range()), format!("a `<{tag}>` has no `name`"))
                    .with_help(format!("give the {tag} a unique `name` attribute")),
            );
            continue;
        };
        // Numeric attributes anywhere inside (visual elements included: urdf-rs reads them).
        for n in item.descendants().filter(|n| n.is_element()) {
            for &(el, attr, count) in NUMERIC {
                if n.tag_name().name() != el {
                    continue;
                }
                let Some(a) = n.attributes().find(|a| a.name() == attr) else { continue };
                let nums: Vec<Option<f64>> = a.value().split_whitespace().map(|t| t.parse::<f64>().ok()).collect();
                if nums.len() == count && nums.iter().all(|x| x.is_some_and(f64::is_finite)) {
                    continue;
                }
                let what = if count == 1 { "a number".to_string() } else { format!("{count} numbers") };
                let mut d = Diagnostic::error(
                    Code::UrdfInvalid,
                    span(a.range_value()),
                    format!("`{attr}` of `<{el}>` in {tag} `{name}` is {}, not {what}", quoted(a.value(), nums.len())),
                );
                d = if a.value().contains("$(") || a.value().contains("${") {
                    d.with_note("this is a xacro substitution that was never expanded: the file was generated by xacro without its arguments or environment")
                        .with_help("expand the xacro (`xacro robot.urdf.xacro > robot.urdf`) or write the numbers here")
                } else {
                    d.with_help(format!("write {what} separated by spaces"))
                };
                diags.push(d);
            }
        }
        if tag == "link" {
            let mut le = LinkElems { range: item.range(), ..Default::default() };
            for c in item.children().filter(|c| c.has_tag_name("collision")) {
                let g = c.children().find(|g| g.has_tag_name("geometry"));
                le.collisions.push(g.map_or(c.range(), |g| g.range()));
                let m = g.and_then(|g| g.children().find(|m| m.has_tag_name("mesh")));
                le.mesh_files.push(
                    m.map(|m| m.attributes().find(|a| a.name() == "filename").map_or(m.range(), |a| a.range_value())),
                );
            }
            out.links.insert(name.to_string(), le);
        } else {
            let mut je = JointElems { range: item.range(), ..Default::default() };
            je.type_attr = item.attributes().find(|a| a.name() == "type").map(|a| a.range());
            je.origin = item.children().find(|c| c.has_tag_name("origin")).map(|c| c.range());
            je.axis = item.children().find(|c| c.has_tag_name("axis")).map(|c| c.range());
            je.mimic = item.children().find(|c| c.has_tag_name("mimic")).map(|c| c.range());
            for need in ["parent", "child"] {
                if !item.children().any(|c| c.has_tag_name(need) && c.attribute("link").is_some()) {
                    diags.push(
                        Diagnostic::error(
                            Code::UrdfInvalid,
                            span(item.range()),
                            format!("joint `{name}` has no `<{need} link=...>`"),
                        )
                        .with_help(format!("add `<{need} link=\"...\"/>` to the joint")),
                    );
                }
            }
            out.joints.insert(name.to_string(), je);
        }
    }
    out
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod hostile;
