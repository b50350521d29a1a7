//! `mochi explain`'s output: a code's title and paragraph, and the list of every code.

use crate::diag::Code;

/// `mochi explain CODE`: the title, a blank line, and the paragraph wrapped at 90 columns.
pub fn explain_text(code: Code) -> String {
    format!("{code}: {}\n\n{}\n", code.title(), wrap(code.explain(), 90))
}

/// `mochi explain --list`: every code and its title, sorted by code.
pub fn code_list_text() -> String {
    let mut codes = Code::ALL.to_vec();
    codes.sort_by_key(|c| c.as_str());
    codes.iter().map(|c| format!("{c}  {}\n", c.title())).collect()
}

/// Greedy word wrap at `width` characters; a longer word gets a line of its own.
pub(super) fn wrap(text: &str, width: usize) -> String {
    let mut out = String::new();
    let mut line_len = 0;
    for word in text.split_whitespace() {
        let n = word.chars().count();
        if line_len > 0 && line_len + 1 + n > width {
            out.push('\n');
            line_len = 0;
        } else if line_len > 0 {
            out.push(' ');
            line_len += 1;
        }
        out.push_str(word);
        line_len += n;
    }
    out
}
