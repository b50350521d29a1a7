//! `mochi project`'s output: local types as text (`local R = T;`) or JSON.

use super::Json;
use serde_json::{json, Value};

/// `mochi project --role R`: R's local type on its own line.
pub fn local_text(local: &str) -> String {
    format!("{}\n", local.trim_end_matches('\n'))
}

/// `mochi project`: every local type as a `local R = T;` line.
pub fn locals_text(locals: &[(&String, &String)]) -> String {
    locals.iter().map(|(role, local)| format!("local {role} = {};\n", local.trim_end())).collect()
}

/// `mochi project --role R --format json`: `{"file", "role", "local"}`.
pub fn local_json(file_name: &str, role: &str, local: &str) -> Json {
    json!({ "file": file_name, "role": role, "local": local })
}

/// `mochi project --format json`: `{"file", "locals": [{"role", "local"}]}`.
pub fn locals_json(file_name: &str, locals: &[(&String, &String)]) -> Json {
    let locals: Vec<Value> = locals.iter().map(|(role, local)| json!({ "role": role, "local": local })).collect();
    json!({ "file": file_name, "locals": locals })
}
