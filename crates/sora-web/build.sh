#!/usr/bin/env bash
# Builds the browser explorer's engine, web/sora_web.wasm, with Debian's
# rustc-web toolchain (packages rustc-web, cargo-web, rust-web-src, lld-19;
# Debian 12 has shipped 1.85 and, in its updates, 1.96; both work):
# rustup's wasm32 standard library comes from the Rust project's servers,
# which CI cannot reach, so the standard library is built from Debian's
# rust-web-src (-Zbuild-std; RUSTC_BOOTSTRAP allows that flag on a stable
# compiler) and linked by LLVM's wasm-ld. Nothing is downloaded but crates.
#
#   sudo apt-get install rustc-web cargo-web rust-web-src lld-19
#   crates/sora-web/build.sh          # then: python3 -m http.server -d web
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
for tool in /usr/bin/rustc /usr/bin/cargo wasm-ld-19; do
    command -v "$tool" >/dev/null || {
        echo "build.sh: $tool is missing: apt-get install rustc-web cargo-web rust-web-src lld-19" >&2
        exit 1
    }
done
[[ -d /usr/lib/rustlib/src/rust/library ]] || {
    echo "build.sh: the standard library's source is missing: apt-get install rust-web-src" >&2
    exit 1
}
cd "$root/crates/sora-web"
# Debian's cargo and rustc, not rustup's (whose rustc has no wasm32 std).
# simd128: WebAssembly's 128-bit SIMD (Chrome 91, Firefox 89, Safari 16.4
# and later), for the loops over wavelengths: measured in headless
# Chromium, a 256-pixel refinement 0.44-0.48 -> 0.36-0.37 s with a high
# sun, 8 % faster with a low one; no fast-math: spectra still agree with the
# native library to 1e-9 (the browser test; 6e-16 measured).
RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 RUSTFLAGS="-C target-feature=+simd128" \
CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld-19 \
CARGO_TARGET_DIR="$root/target/sora-web-wasm" \
    /usr/bin/cargo build --release --locked --lib --target wasm32-unknown-unknown \
    -Zbuild-std=std,panic_abort
wasm="$root/target/sora-web-wasm/wasm32-unknown-unknown/release/sora_web.wasm"
install -m 644 "$wasm" "$root/web/sora_web.wasm.tmp"
mv "$root/web/sora_web.wasm.tmp" "$root/web/sora_web.wasm"
echo "built web/sora_web.wasm: $(stat -c %s "$root/web/sora_web.wasm") bytes, $(gzip -9 -c "$root/web/sora_web.wasm" | wc -c) gzipped"
