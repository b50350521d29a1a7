//! Hostile URDFs and meshes (files users download): each is refused at once with a
//! diagnostic that points into the URDF, or loads with its meaning pinned. None may panic,
//! hang, or take time worse than linear in the file's size. The tests here assert what is
//! refused and where; the times of the same inputs are measured by `cargo bench --bench urdf`
//! (benches/urdf.rs), not asserted by timed unit tests.

use super::tests::{arm, mem_load, one_error, CUBE};
use super::*;

/// `<robot>` holding `n` nested `<a>` elements.
fn nested(n: usize) -> String {
    format!("<robot name=\"r\">{}{}</robot>", "<a>".repeat(n), "</a>".repeat(n))
}

/// A URDF nested deeper than [`crate::xmlscan::MAX_NESTING`] is refused by the pre-scan
/// before roxmltree (which recurses per level) or urdf-rs (quadratic in the depth: 22 s
/// for 200,000 levels) sees it: E0501 at the first start tag past the limit. Before the
/// pre-scan this document was E0505 "the robot has no link", after a long parse.
#[test]
fn deep_nesting_is_refused_at_the_first_element_past_the_limit() {
    let (code, msg, at) = one_error(&nested(200_000), &[]);
    assert_eq!(code, Code::UrdfInvalid, "{msg}");
    // `<robot name="r">` is 16 characters and level 1; the 128th `<a>` is level 129.
    assert_eq!(at, (1, 17 + 127 * 3), "{msg}");
    assert!(msg.contains("128"), "{msg}");
}

/// The limit itself: elements nested exactly [`crate::xmlscan::MAX_NESTING`] deep (robot,
/// link and 126 unknown elements inside the link) load; one level more is refused, inside
/// a link as at the top.
#[test]
fn nesting_up_to_the_limit_loads() {
    let inside = |n: usize| {
        format!("<robot name=\"r\">\n<link name=\"a\">{}{}</link>\n</robot>\n", "<x>".repeat(n), "</x>".repeat(n))
    };
    let (_, r) = mem_load(&inside(126), &[]);
    assert_eq!(r.expect("128 levels load").links.len(), 1);
    let (code, msg, at) = one_error(&inside(127), &[]);
    assert_eq!((code, at), (Code::UrdfInvalid, (2, 16 + 126 * 3)), "{msg}");
    // Comments, CDATA and quoted `>` do not hide nesting, and `/>` elements are not open.
    let tricky = format!(
        "<robot name=\"r\"><link name=\"a\"/>{}<!-- </x></x> -->{}</robot>",
        "<x q=\"/>\"><y/>".repeat(200),
        "</x>".repeat(200)
    );
    let (code, msg, _) = one_error(&tricky, &[]);
    assert!(code == Code::UrdfInvalid && msg.contains("128"), "{code:?} {msg}");
}

/// One element with 100,000 attributes: E0501 at the 65th, at once (roxmltree checks each
/// attribute against the earlier ones: 30 s in a release build; before, the robot loaded
/// after that).
#[test]
fn too_many_attributes_are_refused_at_once() {
    let attrs: String = (0..100_000).map(|k| format!(" a{k}=\"1\"")).collect();
    let urdf = format!("<robot name=\"r\">\n<link name=\"a\"{attrs}/>\n</robot>\n");
    let (code, msg, at) = one_error(&urdf, &[]);
    assert_eq!(code, Code::UrdfInvalid, "{msg}");
    // ` name="a"` is the first attribute, ` a63` the 65th.
    assert_eq!(at, (2, 5 + 9 + (0..63).map(|k: usize| 6 + k.to_string().len()).sum::<usize>() + 2), "{msg}");
    assert!(msg.contains("64"), "{msg}");
}

/// Namespace declarations around many elements that declare one more: the parsers copy or
/// search the namespaces in scope per element (a 5 MB file of 7,200 declarations around
/// 300,000 elements ran for over 5 minutes in a release build). More than 64 declarations:
/// E0501 at the 65th, at once; before, this smaller one loaded.
#[test]
fn too_many_namespaces_are_refused_at_once() {
    let decls = |k: usize| (0..60).map(|i| format!(" xmlns:n{k}_{i}=\"u{k}_{i}\"")).collect::<String>();
    let mut urdf = String::from("<robot name=\"r\">\n<link name=\"a\"/>\n");
    for k in 0..20 {
        urdf += &format!("<e{k}{}>\n", decls(k));
    }
    urdf += &"<x xmlns:z=\"q\"/>".repeat(1000);
    for k in (0..20).rev() {
        urdf += &format!("</e{k}>");
    }
    urdf += "\n</robot>\n";
    let (code, msg, at) = one_error(&urdf, &[]);
    assert_eq!(code, Code::UrdfInvalid, "{msg}");
    assert!(msg.contains("64"), "{msg}");
    // The 65th declaration is the 5th of `<e1>`, on line 4.
    let col = "<e1".len() + decls(1).find(" xmlns:n1_4=").expect("there") + 2;
    assert_eq!(at, (4, col), "{msg}");
}

fn joint_with_origin(xyz: &str) -> String {
    arm("m.obj", "revolute").replace("<axis", &format!("<origin xyz=\"{xyz}\" rpy=\"0 0 0\"/>\n <axis"))
}

/// Numbers that are not finite (overflowing `1e400`, `NaN`, `inf`) are E0501 at the
/// attribute (line 13 of the arm), like any other number that is not one.
#[test]
fn non_finite_numbers_are_refused_at_their_attribute() {
    for xyz in ["1e400 0 0", "NaN 0 0", "0 inf 0", "0 0 -inf", "0 0 -1e309"] {
        let (code, msg, at) = one_error(&joint_with_origin(xyz), &[("/mem/pkg/urdf/m.obj", CUBE)]);
        assert_eq!((code, at.0), (Code::UrdfInvalid, 13), "{xyz}: {msg}");
        assert!(msg.contains("3 numbers"), "{msg}");
    }
    let (code, _, at) = one_error(
        "<robot name=\"r\">\n<link name=\"a\">\n <collision>\n  <geometry><sphere radius=\"nan\"/></geometry>\n </collision>\n</link>\n</robot>\n",
        &[],
    );
    assert_eq!((code, at.0), (Code::UrdfInvalid, 4));
}

/// A million numbers in one attribute: refused, and the message quotes the value cut
/// short (before, the diagnostic carried all 2 MB of it).
#[test]
fn a_million_numbers_are_refused_with_a_short_message() {
    let xyz = vec!["1"; 1_000_000].join(" ");
    let (code, msg, at) = one_error(&joint_with_origin(&xyz), &[("/mem/pkg/urdf/m.obj", CUBE)]);
    assert_eq!((code, at.0), (Code::UrdfInvalid, 13), "{}", &msg[..msg.len().min(200)]);
    assert!(msg.len() < 300, "a message of {} bytes", msg.len());
    assert!(msg.contains("1000000 values"), "{msg}");
}

/// Finite offsets whose sum overflows: each joint origin is 1e308 m up, so the second
/// link's frame would be at infinity and every pose below it NaN (and squared distances
/// overflow long before). Refused (E0530 at the first joint origin beyond the bound of
/// 1e6 m) instead of handing such poses to the geometry.
#[test]
fn offsets_that_overflow_are_refused() {
    let urdf = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<link name=\"c\"/>\n\
        <joint name=\"j1\" type=\"fixed\">\n <parent link=\"a\"/>\n <child link=\"b\"/>\n <origin xyz=\"0 0 1e308\"/>\n</joint>\n\
        <joint name=\"j2\" type=\"fixed\">\n <parent link=\"b\"/>\n <child link=\"c\"/>\n <origin xyz=\"0 0 1e308\"/>\n</joint>\n</robot>\n";
    let (code, msg, at) = one_error(urdf, &[]);
    assert_eq!((code, at.0), (Code::UrdfTooLarge, 8), "{msg}");
    assert!(msg.contains("j1"), "{msg}");
    // 6e5 m each: j1 is within the bound, j2 is not. A prismatic joint's travel and a
    // link's solids count too.
    let (code, msg, at) = one_error(&urdf.replace("1e308", "6e5"), &[]);
    assert_eq!((code, at.0), (Code::UrdfTooLarge, 13), "{msg}");
    assert!(msg.contains("j2") && msg.contains("1.200e6 m"), "{msg}");
    let slide = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n\
        <joint name=\"s\" type=\"prismatic\">\n <parent link=\"a\"/>\n <child link=\"b\"/>\n <origin xyz=\"0 0 1\"/>\n\
        <limit lower=\"-2e6\" upper=\"0\" effort=\"1\" velocity=\"1\"/>\n</joint>\n</robot>\n";
    let (code, msg, at) = one_error(slide, &[]);
    assert_eq!((code, at.0), (Code::UrdfTooLarge, 7), "{msg}");
    assert!(msg.contains("2.000e6 m"), "{msg}");
    let (_, r) = mem_load(&slide.replace("-2e6", "-2"), &[]);
    assert!(r.is_ok());
    let big = "<robot name=\"r\">\n<link name=\"a\">\n <collision><geometry><box size=\"1 3e6 1\"/></geometry></collision>\n</link>\n</robot>\n";
    let (code, msg, at) = one_error(big, &[]);
    assert_eq!((code, at.0), (Code::UrdfTooLarge, 2), "{msg}");
}

/// Joints in a cycle, and a joint whose parent is its child: E0505, at a joint.
#[test]
fn cycles_and_self_parents_are_not_trees() {
    let joint = |n: &str, p: &str, c: &str| {
        format!("<joint name=\"{n}\" type=\"fixed\">\n <parent link=\"{p}\"/>\n <child link=\"{c}\"/>\n</joint>\n")
    };
    let links = "<link name=\"r\"/>\n<link name=\"a\"/>\n<link name=\"b\"/>\n";
    // r is the root; a and b follow each other: not connected to r.
    let urdf = format!("<robot name=\"x\">\n{links}{}{}</robot>\n", joint("ab", "a", "b"), joint("ba", "b", "a"));
    let (code, msg, at) = one_error(&urdf, &[]);
    assert_eq!(code, Code::UrdfNotATree, "{msg}");
    assert!(msg.contains("cycle") && at.0 >= 5, "{msg} at {at:?}");
    // No root at all.
    let urdf = format!(
        "<robot name=\"x\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n{}{}</robot>\n",
        joint("ab", "a", "b"),
        joint("ba", "b", "a")
    );
    let (code, msg, at) = one_error(&urdf, &[]);
    assert!(code == Code::UrdfNotATree && msg.contains("cycle") && at.0 == 4, "{code:?} {msg} at {at:?}");
    // A joint whose parent is its child, alone and beside a proper joint.
    let urdf = format!("<robot name=\"x\">\n<link name=\"a\"/>\n{}</robot>\n", joint("aa", "a", "a"));
    let (code, msg, at) = one_error(&urdf, &[]);
    assert!(code == Code::UrdfNotATree && at.0 == 3, "{code:?} {msg} at {at:?}");
    let urdf = format!("<robot name=\"x\">\n{links}{}{}</robot>\n", joint("ra", "r", "a"), joint("aa", "a", "a"));
    let (code, msg, at) = one_error(&urdf, &[]);
    assert!(code == Code::UrdfNotATree && msg.contains("two joints") && at.0 == 9, "{code:?} {msg} at {at:?}");
}

/// A URDF of `n` links in a chain, each a revolute joint 1 cm above the last.
fn chain(n: usize) -> String {
    let mut s = String::from("<robot name=\"chain\">\n<link name=\"l0\"/>\n");
    for i in 1..n {
        s += &format!(
            "<link name=\"l{i}\"/>\n<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0 0 0.01\"/><axis xyz=\"1 0 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
            i - 1
        );
    }
    s + "</robot>\n"
}

/// 10,000 links in a chain load, and forward kinematics and displacement bounds over them
/// are right at the tip. The walks over the chain do not recurse per link: a recursion
/// 10,000 deep, at a few hundred bytes a frame, overflows the 2 MiB stack of a test thread.
/// That the times are linear in the chain's length (before, [`Robot::new`] kept every link's
/// chain of joints: 5·10^9 indices, 40 GB, at 100,000 links) is measured by
/// `cargo bench --bench urdf` (benches/urdf.rs), 1,000 to 100,000 links side by side.
#[test]
fn a_chain_of_10_000_links_loads_and_its_tip_is_right() {
    let n = 10_000;
    let text = chain(n);
    let (_, r) = mem_load(&text, &[]);
    let robot = r.expect("the chain loads");
    assert_eq!(robot.links.len(), n);
    let q = vec![0.0; n - 1];
    let poses = robot.link_poses(&q);
    let b = robot.displacement_bound(&q, &vec![1e-3; n - 1]);
    assert!((poses[n - 1].translation.vector.z - 0.01 * (n - 1) as f64).abs() < 1e-6);
    // The tip is 0.01·k above joint k (k from the tip): Σ 0.01·k·1e-3 over k < n.
    let tip = 1e-5 * ((n - 1) * (n - 2) / 2) as f64;
    assert!(b[n - 1] >= tip && b[n - 1] < tip * (1.0 + 1e-6), "{} vs {tip}", b[n - 1]);
}

/// Mesh files that are not meshes: empty, truncated, a binary STL whose header claims
/// 10^9 triangles, an OBJ face naming a vertex that does not exist. E0503 at the
/// `filename`, at once (the claimed count is never allocated).
#[test]
fn broken_meshes_are_refused_at_the_filename() {
    let mut huge = vec![0u8; 80];
    huge.extend(1_000_000_000u32.to_le_bytes());
    huge.extend([0u8; 50]);
    let mut solid_huge = huge.clone();
    solid_huge[..6].copy_from_slice(b"solid ");
    let mut truncated = vec![0u8; 80];
    truncated.extend(2u32.to_le_bytes());
    truncated.extend([0u8; 70]);
    let cases: &[(&str, &[u8])] = &[
        ("m.stl", b""),
        ("m.obj", b""),
        ("m.stl", b"solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0"),
        ("m.stl", &truncated),
        ("m.stl", &huge),
        ("m.stl", &solid_huge),
        ("m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"),
        ("m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -99\n"),
    ];
    for (name, bytes) in cases {
        let path = format!("/mem/pkg/urdf/{name}");
        let (code, msg, at) = one_error(&arm(name, "revolute"), &[(&path, bytes)]);
        assert_eq!((code, at), (Code::MeshUnreadable, (6, 20)), "{name} {bytes:?}: {msg}");
    }
}

/// Mesh vertices are finite, and so is the scale, but their product is not (3e38 · 1e300):
/// E0530 at the filename, not a hull of infinite points.
#[test]
fn a_scale_that_overflows_the_mesh_is_refused() {
    let obj = b"v 0 0 0\nv 3e38 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n";
    let urdf = arm("m.obj", "revolute").replace("/>\n  </geometry>", " scale=\"1e300 1 1\"/>\n  </geometry>");
    let (code, msg, at) = one_error(&urdf, &[("/mem/pkg/urdf/m.obj", obj)]);
    assert_eq!((code, at.0), (Code::UrdfTooLarge, 6), "{msg}");
}

/// A mesh path that is a directory (real file system): E0502 at the filename, saying so.
#[test]
fn a_directory_is_not_a_mesh() {
    let dir = std::env::temp_dir().join(format!("mochi-urdf-hostile-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("m.stl")).expect("a temporary folder");
    std::fs::write(dir.join("r.urdf"), arm("m.stl", "revolute")).expect("write the URDF");
    let mut db = SourceDb::new();
    let at = Span::new(db.add("test.chor", "robot"), 0, 5);
    let r = load_robot(&mut db, &dir.join("r.urdf"), at, &mut crate::fsload::read_bytes);
    let _ = std::fs::remove_dir_all(&dir);
    let ds = r.expect_err("a directory is no mesh");
    assert_eq!(ds.len(), 1, "{ds:?}");
    assert_eq!(ds[0].code, Code::GeometryFileMissing);
    assert!(ds[0].message.contains("directory"), "{}", ds[0].message);
    assert_eq!(db.file(ds[0].span.file).line_col(ds[0].span.start as usize), (6, 20));
}

/// Mesh names that leave the URDF's package (`..`, `package://` with `..`, an absolute
/// path) are resolved as ROS resolves them, lexically: mochi reads only regular files of at
/// most 64 MiB and parses them as meshes, so such a name can make it read a file but not
/// show its content (a file that is no mesh is E0503, one that does not exist E0502, both
/// naming the path).
#[test]
fn mesh_paths_that_leave_the_package_are_plain_paths() {
    let escape = "../../../../../../../etc/mochi-nowhere.stl";
    let (code, msg, at) = one_error(&arm(escape, "revolute"), &[]);
    assert_eq!((code, at.0), (Code::GeometryFileMissing, 6), "{msg}");
    assert!(msg.contains("/mem/pkg/urdf/../../../../../../../etc/mochi-nowhere.stl"), "{msg}");
    let secret: &[u8] = b"root:x:0:0:secret\n";
    for name in ["../../etc/passwd.stl", "package://../etc/passwd.stl", "file:///etc/passwd.stl"] {
        let files: &[(&str, &[u8])] = &[
            ("/mem/pkg/urdf/../../etc/passwd.stl", secret),
            ("/mem/pkg/urdf/../etc/passwd.stl", secret),
            ("/etc/passwd.stl", secret),
        ];
        let (code, msg, at) = one_error(&arm(name, "revolute"), files);
        assert_eq!((code, at.0), (Code::MeshUnreadable, 6), "{name}: {msg}");
        assert!(!msg.contains("secret"), "{msg}");
    }
}

/// An empty file, a file cut short, and one that is not UTF-8: E0501 with a span inside
/// the URDF's text (before, an empty file's span was 0..1, past its end, and a bad byte's
/// span cut the replacement character U+FFFD in the middle). Found by the property test of
/// tests/props.rs.
#[test]
fn empty_truncated_and_non_utf8_files_point_inside_them() {
    for bytes in
        [&b""[..], b"<robot name=\"r\"><link name=\"a\"/>", b"<robot name=\"r\">\xff<link name=\"a\"/></robot>"]
    {
        let mut db = SourceDb::new();
        let at = Span::new(db.add("test.chor", "robot"), 0, 5);
        let r = load_robot(&mut db, Path::new("/mem/r.urdf"), at, &mut |_: &Path| Ok(bytes.to_vec()));
        let ds = r.expect_err("rejected");
        assert_eq!(ds.len(), 1, "{ds:?}");
        let f = db.file(ds[0].span.file);
        assert_eq!((ds[0].code, f.name.as_str()), (Code::UrdfInvalid, "/mem/r.urdf"));
        let (s, e) = (ds[0].span.start as usize, ds[0].span.end as usize);
        assert!(s <= e && e <= f.text.len() && f.text.is_char_boundary(s) && f.text.is_char_boundary(e), "{ds:?}");
    }
}
