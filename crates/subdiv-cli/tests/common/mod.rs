//! What the CLI's test files share: running the binary.

// Each test file is a crate of its own and uses its part.
#![allow(dead_code)]

use std::process::{Command, Output};

pub(crate) fn subdiv(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_subdiv")).args(args).output().expect("the binary runs")
}

pub(crate) fn json(args: &[&str]) -> serde_json::Value {
    let output = subdiv(args);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}
