//! The reader on small inputs: values, includes, errors with their positions, and inputs
//! that must not panic it.

use super::*;

const MIN: &str = r#"<?xml version="1.0"?>
<mavlink>
  <enums>
    <enum name="E" bitmask="true">
      <description>An enum.</description>
      <entry value="0x10" name="E_HEX"/>
      <entry value="2**3" name="E_POW"/>
      <entry value="-5" name="E_NEG"/>
    </enum>
  </enums>
  <messages>
    <message id="7" name="M">
      <description>A message.</description>
      <field type="uint16_t" name="a" enum="E" units="m">First.</field>
      <field type="char[8]" name="s">A string.</field>
      <extensions/>
      <field type="float" name="x">Later.</field>
    </message>
  </messages>
</mavlink>
"#;

#[test]
fn reads_values_in_every_form_and_extensions() {
    let d = parse_files("m.xml", &[("m.xml", MIN)]).unwrap();
    assert_eq!(d.name, "m");
    let e = d.enum_("E").unwrap();
    assert!(e.bitmask);
    assert_eq!(e.entries.iter().map(|x| x.value).collect::<Vec<_>>(), [16, 8, -5]);
    let m = d.message("M").unwrap();
    assert_eq!(m.fields.iter().map(|f| f.extension).collect::<Vec<_>>(), [false, false, true]);
    assert_eq!(m.field("a").unwrap().units.as_deref(), Some("m"));
    assert_eq!(m.field("s").unwrap().array, Some(8));
}

#[test]
fn includes_resolve_once_and_cycles_are_harmless() {
    let a = r#"<mavlink><include>b.xml</include><enums><enum name="E"><entry value="1" name="E_A"/></enum></enums></mavlink>"#;
    let b = r#"<mavlink><include>a.xml</include><include>c.xml</include><enums><enum name="E"><entry value="2" name="E_B"/></enum></enums></mavlink>"#;
    let c = r#"<mavlink><messages><message id="1" name="C"/></messages></mavlink>"#;
    let mut asked = Vec::new();
    let fs = [("dir/a.xml", a), ("dir/b.xml", b), ("dir/c.xml", c)];
    let mut load = |n: &str| {
        asked.push(n.to_string());
        fs.iter().find(|(m, _)| *m == n).map(|(_, t)| t.to_string())
    };
    let d = parse("dir/a.xml", &mut load).unwrap();
    assert_eq!(asked, ["dir/a.xml", "dir/b.xml", "dir/c.xml"], "each file once, relative to its includer");
    assert_eq!(d.name, "a");
    // Included first: b's entries precede a's; the enum is merged.
    assert_eq!(d.enum_("E").unwrap().entries.iter().map(|x| x.name.as_str()).collect::<Vec<_>>(), ["E_B", "E_A"]);
    assert_eq!(d.entry("E_A").unwrap().1.value, 1);
    assert!(d.message("C").is_some());
}

#[test]
fn a_file_defined_twice_identically_is_fine() {
    // x includes y and z, both of which define the same message and entry identically (as a
    // dialect that copies a definition would).
    let x = r#"<mavlink><include>y.xml</include><include>z.xml</include></mavlink>"#;
    let y = r#"<mavlink><enums><enum name="E"><entry value="1" name="E_A"/></enum></enums><messages><message id="1" name="C"><field type="uint8_t" name="f">F</field></message></messages></mavlink>"#;
    let d = parse_files("x.xml", &[("x.xml", x), ("y.xml", y), ("z.xml", y)]).unwrap();
    assert_eq!((d.messages.len(), d.enum_("E").unwrap().entries.len()), (1, 1));
}

/// `(line, column)` of the first occurrence of `needle` in `text`, 1-based.
fn pos(text: &str, needle: &str) -> (u32, u32) {
    let at = text.find(needle).unwrap_or_else(|| panic!("{needle:?} not in the text"));
    let line = text[..at].matches('\n').count() as u32 + 1;
    let col = text[..at].rsplit('\n').next().unwrap().chars().count() as u32 + 1;
    (line, col)
}

fn assert_err_at(e: &DialectError, file: &str, at: (u32, u32), says: &str) {
    assert_eq!((e.file.as_str(), e.line, e.col), (file, at.0, at.1), "{e}");
    assert!(e.message.contains(says), "{e} should say {says:?}");
    assert_eq!(e.to_string(), format!("{file}:{}:{}: {}", at.0, at.1, e.message));
}

#[test]
fn errors_have_positions() {
    // Malformed XML: roxmltree's position.
    let bad = "<mavlink>\n  <enums>\n  </enum>\n</mavlink>";
    let e = err("m.xml", &[("m.xml", bad)]);
    assert_eq!((e.file.as_str(), e.line), ("m.xml", 3), "{e}");
    assert!(e.message.contains("malformed XML"), "{e}");

    // Unknown wire type: at the attribute's value.
    let t = MIN.replace(r#"type="uint16_t""#, r#"type="uint17_t""#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "uint17_t"), "unknown wire type `uint17_t`");
    let t = MIN.replace("char[8]", "char[0]");
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "char[0]"), "array length");
    let t = MIN.replace("char[8]", "char[08]");
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "char[08]"), "array length");
    let t = MIN.replace("char[8]", "uint8_t_mavlink_version[2]");
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "uint8_t_mavlink_version"), "single byte");

    // Entry values that are not numbers.
    for v in ["ten", "0x", "2**", "1.5", "99999999999999999999", "2**64", ""] {
        let t = MIN.replace(r#"value="0x10""#, &format!(r#"value="{v}""#));
        let e = err("m.xml", &[("m.xml", &t)]);
        assert_err_at(&e, "m.xml", pos(&t, &format!(r#"{v}" name="E_HEX""#)), "is not an integer");
    }
    let t = MIN.replace(r#"<entry value="0x10" name="E_HEX"/>"#, r#"<entry name="E_HEX"/>"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "<entry name"), "has no value");

    // A missing include: at the <include> of the including file.
    let t = MIN.replace("<mavlink>", "<mavlink>\n  <include>gone.xml</include>");
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "<include>"), "`gone.xml` is not there");
    // A missing root: no position.
    let e = err("none.xml", &[]);
    assert_eq!((e.file.as_str(), e.line, e.to_string()), ("none.xml", 0, "none.xml: no such definition file".into()));

    // Duplicates with different content: at the second definition, naming the first.
    let dup = MIN.replace("</messages>", "  <message id=\"8\" name=\"M\"/>\n  </messages>");
    let e = err("m.xml", &[("m.xml", &dup)]);
    assert_err_at(&e, "m.xml", pos(&dup, r#"<message id="8""#), "message M is defined again");
    assert!(e.message.contains(&format!("first at m.xml:{}:{}", pos(&dup, r#"<message id="7""#).0, 5)), "{e}");
    let dup = MIN.replace("</messages>", "  <message id=\"7\" name=\"N\"/>\n  </messages>");
    assert_err_at(&err("m.xml", &[("m.xml", &dup)]), "m.xml", pos(&dup, r#"<message id="7" name="N""#), "the id of M");
    let dup = MIN.replace("</enums>", "  <enum name=\"F\"><entry value=\"1\" name=\"E_POW\"/></enum>\n  </enums>");
    let e = err("m.xml", &[("m.xml", &dup)]);
    assert_err_at(&e, "m.xml", pos(&dup, r#"<entry value="1" name="E_POW""#), "also an entry of E");
    let dup = MIN.replace("</enums>", "  <enum name=\"E\"><entry value=\"9\" name=\"E_POW\"/></enum>\n  </enums>");
    assert_err_at(&err("m.xml", &[("m.xml", &dup)]), "m.xml", pos(&dup, r#"<entry value="9""#), "defined again");
    let dup = MIN.replace(r#"name="s""#, r#"name="a""#);
    assert_err_at(
        &err("m.xml", &[("m.xml", &dup)]),
        "m.xml",
        pos(&dup, r#"<field type="char[8]""#),
        "two fields named a",
    );

    // Ids and attributes.
    let t = MIN.replace(r#"id="7""#, r#"id="16777216""#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "16777216"), "24 bits");
    let t = MIN.replace(r#"<message id="7" name="M">"#, r#"<message name="M">"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, r#"<message name"#), "no `id` attribute");
    let t = MIN.replace(r#"bitmask="true""#, r#"bitmask="yes""#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", pos(&t, "yes"), "not `true` or `false`");
    let t = "<mavlink>\n</mavlink>".replace("mavlink", "mavlonk");
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", (1, 1), "not <mavlink>");
    // No DTD (no entity expansion).
    let t = "<!DOCTYPE mavlink [<!ENTITY a \"aaaa\">]>\n<mavlink/>";
    assert!(err("m.xml", &[("m.xml", t)]).message.contains("malformed XML"));
}

#[test]
fn command_parameter_errors() {
    let cmd = |p: &str| {
        format!(
            "<mavlink>\n<enums>\n<enum name=\"MAV_CMD\">\n<entry value=\"1\" name=\"C\">\n{p}\n</entry>\n</enum>\n</enums>\n</mavlink>"
        )
    };
    let t = cmd(r#"<param index="8">x</param>"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", (5, 15), "not one of 1..=7");
    let t = cmd(r#"<param index="1">x</param><param index="1">y</param>"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", (5, 27), "two params of index 1");
    let t = cmd(r#"<param index="1" minValue="NaN">x</param>"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", (5, 28), "not a finite number");
    let t = cmd(r#"<param index="1" reserved="maybe">x</param>"#);
    assert_err_at(&err("m.xml", &[("m.xml", &t)]), "m.xml", (5, 28), "not `true` or `false`");
    let t = cmd(
        r#"<param index="2" label="Yaw Angle" minValue="-180" maxValue="180" units="deg">y</param><param index="1" reserved="true" default="NaN">x</param>"#,
    );
    let d = parse_files("m.xml", &[("m.xml", &t)]).unwrap();
    let x = d.entry("C").unwrap().1;
    assert_eq!(x.params.iter().map(|p| p.index).collect::<Vec<_>>(), [1, 2], "sorted by index");
    assert!(x.params[0].reserved);
    let yaw = x.param_by_name("yaw_angle").unwrap();
    assert_eq!((yaw.min, yaw.max, yaw.units.as_deref()), (Some(-180.0), Some(180.0), Some("deg")));
}

#[test]
fn include_depth_is_bounded() {
    // A loader that makes up a new file for every name: the reader stops with an error.
    let mut load = |n: &str| Some(format!("<mavlink><include>{n}x</include></mavlink>"));
    let e = parse("f", &mut load).unwrap_err();
    assert!(e.message.contains("nest deeper"), "{e}");
}

// ---- no panics ----

/// The shared pre-scan's other limits ([`crate::xmlscan`]): an element with 100,000
/// attributes (quadratic in roxmltree) and a flood of namespace declarations are refused at
/// once, at the first one past the limit.
#[test]
fn attribute_and_namespace_floods_are_refused_before_parsing() {
    let attrs: String = (0..100_000).map(|k| format!(" a{k}=\"{k}\"")).collect();
    let t = format!("<mavlink><enums{attrs}/></mavlink>");
    let e = err("m.xml", &[("m.xml", &t)]);
    assert!(e.message.contains("more than 64 attributes"), "{e}");
    assert_eq!((e.line, e.col), (1, (17 + " a0=\"0\"".len() * 10 + " a10=\"10\"".len() * 54) as u32), "{e}");
    let ns: String = (0..1_000).map(|k| format!("<e xmlns:p{k}=\"u\"/>")).collect();
    let e = err("m.xml", &[("m.xml", &format!("<mavlink>{ns}</mavlink>"))]);
    assert!(e.message.contains("more than 64 namespace declarations"), "{e}");
}

#[test]
fn deep_nesting_does_not_overflow() {
    let deep = |n: usize| format!("{}x{}", "<d>".repeat(n), "</d>".repeat(n));
    let t = format!(
        "<mavlink><enums><enum name=\"E\"><description>{}</description><entry value=\"1\" name=\"E_A\"/></enum></enums>{}</mavlink>",
        deep(50_000),
        deep(50_000)
    );
    let e = err("m.xml", &[("m.xml", &t)]);
    assert!(e.message.contains("nest deeper than 128"), "{e}");
    // The 129th open element: <mavlink>, <enums>, <enum>, <description> and the 125th <d>.
    assert_eq!((e.line, e.col), (1, 45 + 3 * 124), "{e}");
    // Close tags hidden where roxmltree does not see them do not hide the depth.
    for hide in ["<!--</d>-->", "<![CDATA[</d>]]>", "<?pi </d>?>", "<e a=\"/>\"></e>"] {
        let t = format!("<mavlink>{}</mavlink>", format!("<d>{hide}").repeat(50_000));
        let e = err("m.xml", &[("m.xml", &t)]);
        assert!(e.message.contains("nest deeper"), "{hide}: {e}");
    }
    // `/>` elements and attributes with `>` in them nest nothing.
    let t = format!("<mavlink>{}</mavlink>", "<d a=\">\" b='/'/>".repeat(50_000));
    assert!(parse_files("m.xml", &[("m.xml", &t)]).is_ok());
    let t = format!("<mavlink>{}x{}</mavlink>", "<d>".repeat(127), "</d>".repeat(127));
    assert!(parse_files("m.xml", &[("m.xml", &t)]).is_ok(), "128 deep with <mavlink> is allowed");
}

/// Bits of MAVLink XML a mutation splices in.
const PIECES: &[&str] = &[
    "<",
    ">",
    "/>",
    "</",
    "\"",
    "=",
    "&",
    "&amp;",
    "<![CDATA[",
    "]]>",
    "<!--",
    "-->",
    "<?xml?>",
    "<include>",
    "</include>",
    "minimal.xml",
    "standard.xml",
    "common.xml",
    "<enum name=\"MAV_CMD\">",
    "</enum>",
    "<entry ",
    "value=\"",
    "2**",
    "0x",
    "-",
    "99999999999999999999999",
    "name=\"",
    "<message id=\"",
    "</message>",
    "<field type=\"",
    "char[",
    "[0]",
    "[999]",
    "uint8_t_mavlink_version",
    "<extensions/>",
    "<param index=\"",
    "minValue=\"",
    "NaN",
    "reserved=\"",
    "bitmask=\"",
    "\u{0}",
    "\u{feff}",
    "\r\n",
    "é",
    "<!DOCTYPE a>",
];

fn mutate(base: &str, edits: &[(usize, usize, usize)]) -> String {
    let mut bytes = base.as_bytes().to_vec();
    for &(at, len, piece) in edits {
        let at = at % (bytes.len() + 1);
        let end = (at + len % 64).min(bytes.len());
        match piece % 3 {
            0 => {
                bytes.drain(at..end);
            }
            1 => {
                let p = PIECES[piece / 3 % PIECES.len()].as_bytes();
                bytes.splice(at..at, p.iter().copied());
            }
            _ => {
                let copy = bytes[at..end].to_vec();
                bytes.splice(at..at, copy);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let _ = parse_files("x.xml", &[("x.xml", &text)]);
        let wrapped = format!("<mavlink>{text}</mavlink>");
        let _ = parse_files("x.xml", &[("x.xml", &wrapped)]);
    }

    /// Mutated real definitions (minimal and standard with their includes, and a mutated
    /// include tree under common): an error or a dialect, never a panic; an error always has
    /// a position within its file.
    #[test]
    fn mutated_real_xml_never_panics(
        which in 0usize..3,
        edits in proptest::collection::vec((any::<usize>(), any::<usize>(), any::<usize>()), 1..8),
    ) {
        let (root, target) = [("minimal.xml", "minimal.xml"), ("standard.xml", "standard.xml"), ("standard.xml", "minimal.xml")][which];
        let base = builtin::bundled(target).unwrap();
        let mutated = mutate(&base, &edits);
        let mut load = |n: &str| if n == target { Some(mutated.clone()) } else { builtin::bundled(n) };
        if let Err(e) = parse(root, &mut load) {
            let text = if e.file == target { mutated.clone() } else { builtin::bundled(&e.file).unwrap_or_default() };
            prop_assert!(e.line as usize <= text.lines().count() + 1, "{e}");
            prop_assert!(!e.message.is_empty());
        }
    }
}

/// The enum summaries the entry predicate of enum-typed fields is built from: runs of consecutive values
/// and the bits of a bitmask's flags.
#[test]
fn enums_summarise_as_runs_and_flag_masks() {
    let d = common();
    let e = |n: &str| d.enum_(n).unwrap_or_else(|| panic!("{n}"));
    assert_eq!(e("MAV_RESULT").value_runs(), vec![(0, 10)]);
    assert_eq!(e("MAV_MISSION_TYPE").value_runs(), vec![(0, 2), (255, 255)]);
    assert_eq!(e("MAV_PARAM_TYPE").value_runs(), vec![(1, 10)]);
    assert!(e("MAV_CMD").value_runs().len() < e("MAV_CMD").entries.len() / 2);
    assert_eq!(e("MAV_MODE_FLAG").flag_mask(8), 0xff);
    assert_eq!(e("ATTITUDE_TARGET_TYPEMASK").flag_mask(8), 0b1110_0111);
    assert_eq!(e("MAV_BOOL").flag_mask(8), 1);
    // Duplicated and negative values, and the width: an enum built by hand.
    let entry =
        |name: &str, value: i64| Entry { name: name.into(), value, params: Vec::new(), description: String::new() };
    let odd = Enum {
        name: "ODD".into(),
        bitmask: true,
        entries: vec![entry("A", 3), entry("B", 3), entry("C", -1), entry("D", 4), entry("E", i64::MAX)],
        description: String::new(),
    };
    assert_eq!(odd.value_runs(), vec![(-1, -1), (3, 4), (i64::MAX, i64::MAX)]);
    assert_eq!(odd.flag_mask(8), 0xff);
    assert_eq!(odd.flag_mask(64), u64::MAX);
}
