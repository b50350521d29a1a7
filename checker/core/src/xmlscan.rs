//! A linear scan of an XML text that bounds its shape before any XML parser sees it: the
//! URDF reader (`geometry::urdf`, whose files users download) and the MAVLink dialect reader
//! (`dialect::xml`) both run it first.
//!
//! The parsers behind them are not linear in every dimension of a document: roxmltree recurses per level of nesting (a document nested tens of thousands
//! deep exhausts the stack) and checks each attribute against the element's earlier ones
//! (quadratic in attributes per element: 30 s for one element with 100,000 attributes);
//! RustyXML, which urdf-rs parses with, looks each element's namespace up through one map
//! per open element (quadratic in the depth: 22 s for 200,000 levels); and the namespaces
//! in scope are copied or searched per element (a 5 MB file that declares 7,200 namespaces
//! around 300,000 elements each declaring one more ran for over 5 minutes). URDFs nest
//! about 6 deep, give an element at most 6 attributes and declare a few namespaces, so the
//! scan refuses documents nested deeper than [`MAX_NESTING`] (MAVLink's definitions nest 6
//! deep), with an element of more than [`MAX_ATTRIBUTES`] attributes, or
//! with more than [`MAX_NAMESPACES`] namespace declarations; then every parser's work is
//! linear in the file's size (each step bounded by these constants).
//!
//! The scan follows roxmltree's tokens (comments to `-->`, CDATA to `]]>`, processing instructions to `?>`, declarations to `>`, quoted
//! attribute values, `/>` empty elements) and never counts fewer open elements, or fewer
//! attributes, than roxmltree would hold at the same point: a close tag hidden in a comment
//! or a `/>` inside an attribute value closes nothing here either. Where the two could
//! differ (malformed input), roxmltree stops with an error at that point. It is byte
//! scanning only: no XML crate is named here (tests/tidy.rs).

/// How deep elements may nest.
pub const MAX_NESTING: usize = 128;

/// How many attributes one element may have (URDF's `<inertia>` has the most: 6; a
/// MAVLink `<field>` at most a dozen).
pub const MAX_ATTRIBUTES: usize = 64;

/// How many namespace declarations (`xmlns`, `xmlns:p` attributes) a document may hold
/// (URDFs declare a few: `xacro`, Gazebo's `sensor`, `controller`, `interface`).
pub const MAX_NAMESPACES: usize = 64;

/// What the scan found first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Excess {
    /// The byte offset of the first start tag nested deeper than [`MAX_NESTING`].
    Depth(usize),
    /// The byte offset of the first attribute past [`MAX_ATTRIBUTES`] of one element.
    Attributes(usize),
    /// The byte offset of the first namespace declaration past [`MAX_NAMESPACES`].
    Namespaces(usize),
}

/// The first place where `text` exceeds a limit, if any. Linear in `text`'s length.
pub fn excess(text: &str) -> Option<Excess> {
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| -> usize {
        b.get(from..)
            .and_then(|r| r.windows(pat.len()).position(|w| w == pat))
            .map_or(b.len(), |k| from + k + pat.len())
    };
    let (mut i, mut depth, mut namespaces) = (0, 0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        i = if rest.starts_with(b"<!--") {
            find(i + 4, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            find(i + 9, b"]]>")
        } else if rest.starts_with(b"<?") {
            find(i + 2, b"?>")
        } else if rest.starts_with(b"<!") {
            find(i + 2, b">")
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            find(i + 2, b">")
        } else {
            // A start tag: every attribute has a quoted value, so opening quotes count them;
            // `name_start` is where the last name after white space began (roxmltree wants
            // white space before each attribute).
            let (mut j, mut quote, mut empty, mut attrs) = (i + 1, None, false, 0usize);
            let (mut name_start, mut fresh) = (j, false);
            while j < b.len() {
                let c = b[j];
                match quote {
                    Some(q) if c == q => quote = None,
                    Some(_) if c == b'<' => break,
                    Some(_) => {}
                    None if c == b'"' || c == b'\'' => {
                        quote = Some(c);
                        attrs += 1;
                        if attrs > MAX_ATTRIBUTES {
                            return Some(Excess::Attributes(name_start));
                        }
                        if b[name_start..].starts_with(b"xmlns") {
                            namespaces += 1;
                            if namespaces > MAX_NAMESPACES {
                                return Some(Excess::Namespaces(name_start));
                            }
                        }
                    }
                    None if c == b'>' => {
                        empty = b[j - 1] == b'/';
                        j += 1;
                        break;
                    }
                    None if c == b'<' => break,
                    None if c.is_ascii_whitespace() => fresh = true,
                    None if c == b'=' => {}
                    None => {
                        if fresh {
                            (name_start, fresh) = (j, false);
                        }
                    }
                }
                j += 1;
            }
            if !empty {
                depth += 1;
                if depth > MAX_NESTING {
                    return Some(Excess::Depth(i));
                }
            }
            j
        };
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_what_does_not_count() {
        let deep = |n: usize| format!("<r>{}{}</r>", "<a>".repeat(n), "</a>".repeat(n));
        assert_eq!(excess(&deep(MAX_NESTING - 1)), None);
        assert_eq!(excess(&deep(MAX_NESTING)), Some(Excess::Depth(3 + 3 * (MAX_NESTING - 1))));
        // Empty elements, closed elements and tags in comments, CDATA, processing
        // instructions and declarations do not nest.
        let flat = "<r>".to_string() + &"<a/><b></b><!-- <c> --><![CDATA[<d>]]><?pi <e>?><!X <f>>".repeat(500) + "</r>";
        assert_eq!(excess(&flat), None);
        // A `/>` or `>` inside a quoted value does not end the tag.
        let quoted = format!("<r>{}", "<a q=\"/>\" s='>'>".repeat(MAX_NESTING));
        assert_eq!(excess(&quoted), Some(Excess::Depth(3 + 16 * (MAX_NESTING - 1))));
        let attrs = |n: usize| format!("<r{}/>", (0..n).map(|k| format!(" a{k}=\"{k}\"")).collect::<String>());
        assert_eq!(excess(&attrs(MAX_ATTRIBUTES)), None);
        let many = attrs(MAX_ATTRIBUTES + 1);
        let at = many.find(&format!(" a{MAX_ATTRIBUTES}=")).unwrap() + 1;
        assert_eq!(excess(&many), Some(Excess::Attributes(at)));
        // Namespace declarations, wherever they are; `xmlns = "..."` with spaces counts too.
        let ns = |n: usize| {
            format!("<r>{}</r>", (0..n).map(|k| format!("<a xmlns:p{k}=\"u\" b=\"1\"/>")).collect::<String>())
        };
        assert_eq!(excess(&ns(MAX_NAMESPACES)), None);
        let many = ns(MAX_NAMESPACES + 1);
        let at = many.find(&format!("xmlns:p{MAX_NAMESPACES}=")).unwrap();
        assert_eq!(excess(&many), Some(Excess::Namespaces(at)));
        let spaced = "<r>".to_string() + &"<a xmlns = 'u'/>".repeat(MAX_NAMESPACES + 1) + "</r>";
        assert_eq!(excess(&spaced), Some(Excess::Namespaces(3 + 16 * MAX_NAMESPACES + 3)));
        // Unterminated constructs end the scan without a panic.
        for t in ["<", "<a", "<a q=\"", "<!--", "<![CDATA[", "<?", "<!", "</", "<a/", "<a='>"] {
            let _ = excess(t);
        }
    }
}
