//! Runs one explorer request natively (the same engine as the browser's,
//! compiled for this machine) and prints its JSON reply: the browser test
//! compares the page's numbers with these.
//!
//! ```text
//! echo '{"op": "presets"}' | cargo run --example request
//! ```

use std::io::Read;

fn main() {
    let mut request = Vec::new();
    if let Err(error) = std::io::stdin().read_to_end(&mut request) {
        eprintln!("request: cannot read stdin: {error}");
        std::process::exit(2);
    }
    let reply = sora_web::engine::Engine::default().call_bytes(&request);
    println!("{}", reply.json);
    if reply.is_error {
        std::process::exit(1);
    }
}
