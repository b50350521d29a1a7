//! Tests of the dialect reader against the bundled MAVLink definitions, of its errors and
//! of the lookups.

use super::*;

#[test]
fn every_bundled_dialect_reads() {
    for n in builtin_names() {
        if let Err(e) = parse(&format!("{n}.xml"), &mut builtin::bundled) {
            panic!("{n}: {e}");
        }
        assert!(builtin(n).is_some(), "{n}");
    }
}
