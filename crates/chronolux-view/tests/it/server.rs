//! The web server over real sockets: loopback by default, fixed routes (404 for anything
//! else, in particular paths that try to leave the page's assets), edits through
//! `POST /api/edit`, images and the queue through server-sent events.

use crate::{demo, node, small_options};
use chronolux_core::scene::stage;
use chronolux_view::{DEFAULT_BIND, Running, bind, start};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

fn serve() -> Running {
    let (scene, frame) = demo();
    let listener = bind(SocketAddr::new(DEFAULT_BIND, 0)).expect("a free port on loopback");
    start(listener, scene, frame, small_options()).expect("the viewer starts")
}

/// One request with `Connection: close`; returns (status code, body).
fn request(addr: SocketAddr, method: &str, path: &str, body: &str) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let code = out
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("no status line in {out:?}"));
    let body = out
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_string();
    (code, body)
}

#[test]
fn the_default_interface_is_loopback() {
    assert!(DEFAULT_BIND.is_loopback());
    let v = serve();
    assert!(v.addr.ip().is_loopback(), "{}", v.addr);
    v.stop().unwrap();
}

#[test]
fn only_the_fixed_routes_answer() {
    let v = serve();
    let (code, page) = request(v.addr, "GET", "/", "");
    assert_eq!(code, 200);
    assert!(page.contains("<title>chronolux view</title>"));
    let (code, info) = request(v.addr, "GET", "/api/scene", "");
    assert_eq!(code, 200);
    let info: Value = serde_json::from_str(&info).unwrap();
    assert!(
        info["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n["name"] == "metal_sphere")
    );
    for path in [
        "/../Cargo.toml",
        "/Cargo.toml",
        "/%2e%2e/%2e%2e/Cargo.toml",
        "/assets/index.html",
        "/index.html",
        "/api/../../../../etc/passwd",
        "/src/lib.rs",
        "/api/scene/..",
    ] {
        assert_eq!(request(v.addr, "GET", path, "").0, 404, "{path}");
    }
    v.stop().unwrap();
}

#[test]
fn a_port_in_use_is_a_one_line_error() {
    let v = serve();
    let err = bind(v.addr).expect_err("the port is taken");
    let msg = format!("{err:#}");
    assert!(
        msg.contains("cannot listen on") && !msg.contains('\n'),
        "{msg}"
    );
    v.stop().unwrap();
}

/// Reads server-sent `frame` events until `done` accepts a status; returns the images
/// seen (data URLs) and the last status.
fn watch_events(
    addr: SocketAddr,
    timeout: Duration,
    mut done: impl FnMut(&Value) -> bool,
) -> (Vec<String>, Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(s, "GET /api/events HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut r = BufReader::new(s);
    let t0 = Instant::now();
    let mut images = Vec::new();
    let mut line = String::new();
    loop {
        assert!(
            t0.elapsed() < timeout,
            "no matching status within {timeout:?}"
        );
        // A read that times out keeps what it read in `line`; it is cleared only once a
        // whole line has been handled.
        match r.read_line(&mut line) {
            Ok(0) => panic!("the event stream ended"),
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => continue,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
            Err(e) => panic!("{e}"),
        }
        let data = line.trim_end().strip_prefix("data: ").map(str::to_string);
        line.clear();
        let Some(data) = data else {
            continue;
        };
        let msg: Value = serde_json::from_str(&data).expect("frame data is JSON");
        images.push(msg["image"].as_str().unwrap().to_string());
        if done(&msg["status"]) {
            return (images, msg["status"].clone());
        }
    }
}

#[test]
fn an_edit_streams_a_new_image_and_the_queue_drains_to_zero() {
    let v = serve();
    let max_spp = small_options().max_spp;
    // Idle before the edit: nothing queued and the image at max_spp, where it stops
    // changing (the pass index picks the samples, so this image is deterministic).
    let idle = |s: &Value| s["queued"] == 0 && s["spp"] == max_spp;
    let (before, _) = watch_events(v.addr, Duration::from_secs(120), idle);
    let before = before.last().unwrap().clone();
    assert!(before.starts_with("data:image/png;base64,"));
    let (code, body) = request(
        v.addr,
        "POST",
        "/api/edit",
        r#"{"kind":"node","node":99999,"translate":[0,0,0],"rotate":[0,0,0]}"#,
    );
    assert_eq!(code, 400, "{body}");
    assert!(body.contains("no node"));
    let sphere = node(&stage::demo(), "metal_sphere");
    let edit =
        format!(r#"{{"kind":"node","node":{sphere},"translate":[0.3,0,0],"rotate":[0,0,0]}}"#);
    let (code, body) = request(v.addr, "POST", "/api/edit", &edit);
    assert_eq!(code, 200, "{body}");
    let id = serde_json::from_str::<Value>(&body).unwrap()["id"]
        .as_u64()
        .unwrap();
    let (images, last) = watch_events(v.addr, Duration::from_secs(120), |s| {
        s["edit"].as_u64() == Some(id) && idle(s)
    });
    assert!(last["settled_after"].is_number(), "{last}");
    assert!(last["invalidated"].as_u64() > Some(0), "{last}");
    assert_ne!(
        images.last().unwrap(),
        &before,
        "the idle image after the move differs from the one before"
    );
    v.stop().unwrap();
}
