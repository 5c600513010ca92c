#!/usr/bin/env bash
# The viewer in a web browser: the same kernel and panel on WebGPU.
#
#   ./scripts/web.sh build         builds the page into target/web/, a static
#                                  folder that any web server can host
#   ./scripts/web.sh serve [PORT]  builds it and serves it on
#                                  http://127.0.0.1:PORT/ (default 8000)
#   ./scripts/web.sh test          builds it, serves it, and checks it in
#                                  headless Chromium with WebGPU on SwiftShader
#
# Needs Rust (rustup); installs the wasm32 target and the wasm-bindgen CLI
# that matches Cargo.lock. The test also needs Node.js and Chromium (on
# Debian: apt-get install chromium nodejs npm), and installs the rest.
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=target/web
WASM=target/wasm32-unknown-unknown/release/pt_web.wasm

# The wasm-bindgen CLI must be the version of the wasm-bindgen crate.
bindgen_version() {
    awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock
}

tools() {
    if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
        rustup target add wasm32-unknown-unknown
    fi
    local want have
    want=$(bindgen_version)
    have=$(wasm-bindgen --version 2>/dev/null | awk '{ print $2 }' || true)
    if [ "$have" != "$want" ]; then
        echo "installing wasm-bindgen-cli $want (have: ${have:-none})" >&2
        cargo install --quiet wasm-bindgen-cli --version "$want"
    fi
}

build() {
    tools
    cargo build --release -p pt-web --target wasm32-unknown-unknown
    rm -rf "$OUT.tmp"
    mkdir -p "$OUT.tmp"
    wasm-bindgen --target web --no-typescript --out-dir "$OUT.tmp" "$WASM"
    cp web/static/index.html "$OUT.tmp/"
    rm -rf "$OUT"
    mv "$OUT.tmp" "$OUT"
    echo "built $OUT/ ($(du -sh "$OUT" | cut -f1)); serve it with ./scripts/web.sh serve" >&2
}

serve() {
    local port=${1:-8000}
    echo "serving $OUT/ on http://127.0.0.1:$port/ (a browser with WebGPU; Ctrl-C stops)" >&2
    exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$OUT"
}

free_port() {
    python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

json() {
    python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"
}

test_page() {
    command -v chromium >/dev/null || { echo "the web test needs Chromium: apt-get install chromium" >&2; exit 1; }
    command -v npm >/dev/null || { echo "the web test needs Node.js: apt-get install nodejs npm" >&2; exit 1; }
    build
    (cd web/test && npm ci --silent --no-audit --no-fund)
    cargo build --release -p pathtracer
    local bin=$PWD/target/release/pathtracer port
    # Globals: the exit trap runs after this function has returned.
    WEB_TEST_DIR=$(mktemp -d)
    local dir=$WEB_TEST_DIR
    port=$(free_port)
    python3 -m http.server "$port" --bind 127.0.0.1 --directory "$OUT" >"$dir/server.log" 2>&1 &
    WEB_TEST_SERVER=$!
    trap 'kill "$WEB_TEST_SERVER" 2>/dev/null; rm -rf "$WEB_TEST_DIR"' EXIT
    for _ in $(seq 50); do
        python3 -c 'import sys, urllib.request; urllib.request.urlopen(sys.argv[1])' \
            "http://127.0.0.1:$port/index.html" 2>/dev/null && break
        sleep 0.2
    done

    # The default scene with a negative light radius, for the drop test.
    sed 's/^radius = 0.15$/radius = -0.15/' scenes/default.toml >"$dir/bad.toml"
    if cmp -s scenes/default.toml "$dir/bad.toml"; then
        echo "web test: no light radius to break in scenes/default.toml" >&2
        exit 1
    fi
    node web/test/run.mjs "http://127.0.0.1:$port/index.html" "$dir" "$dir/bad.toml"

    # The page's image against the CPU backend: an independent seed, 4x the
    # samples, region by region. Each region's paired t statistic is a
    # standard normal draw when both are unbiased estimates of the same
    # image; |t| > 5 has probability 6e-7 per region and channel.
    local w h
    w=$(json "$dir/result.json" width)
    h=$(json "$dir/result.json" height)
    "$bin" render --backend cpu --width "$w" --height "$h" --spp 256 --seed 1 --out "$dir/cpu.exr"
    "$bin" compare "$dir/page.exr" --reference "$dir/cpu.exr" --block 16 --max-t 5

    # The dropped file's error is the command line's, and the scene stayed.
    local cli page
    cli=$(cd "$dir" && "$bin" render --scene bad.toml --out bad.png 2>&1 >/dev/null | head -n 1 || true)
    page=$(json "$dir/result.json" dropStatus)
    if [ "$cli" != "$page" ]; then
        printf 'web test: the page shows\n  %s\nbut the command line prints\n  %s\n' "$page" "$cli" >&2
        exit 1
    fi
    [ "$(json "$dir/result.json" sceneKept)" = True ] || { echo "web test: a bad drop replaced the scene" >&2; exit 1; }
    [ -e "$dir/bad.png" ] && { echo "web test: a bad scene wrote an image" >&2; exit 1; }
    # The panel: the image starts right of it (points).
    python3 -c 'import json, sys; w = json.load(open(sys.argv[1]))["panelWidth"]; sys.exit(0 if w > 100 else f"web test: no panel (image at x = {w})")' \
        "$dir/result.json"

    cp "$dir/shot.png" docs/web-viewer.png
    speed "$bin" "$dir" "$w" "$h"
    echo "web test passed: ${w}x${h}, $(json "$dir/result.json" spp) spp, $(json "$dir/result.json" samplesPerSecond) samples/s on $(json "$dir/result.json" adapter); screenshot in docs/web-viewer.png" >&2
}

# Samples per second of the page (its frames' GPU time, from the queue's
# completion callbacks) beside the native backends on the same image size,
# samples and samples per frame, in the same run: docs/web-speed.md, which
# docs/PERFORMANCE.md includes.
speed() {
    local bin=$1 dir=$2 w=$3 h=$4 spp per_frame=4 row backend sps
    spp=$(json "$dir/result.json" spp)
    {
        echo "Default scene, ${w}x${h} pixels (the image area of a 640x360 page beside the panel), $spp spp in frames of $per_frame, 5 bounces; measured by \`./scripts/web.sh test\` on $(date -u +%Y-%m-%d), in one run, on $(nproc) cores ($(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo))."
        echo
        echo "| renderer | samples/s | ratio to the browser |"
        echo "|---|---|---|"
        local page
        page=$(json "$dir/result.json" samplesPerSecond)
        printf '| browser: %s, WebGPU on SwiftShader | %.3e | 1 |\n' "$(chromium --version 2>/dev/null)" "$page"
        for backend in gpu cpu; do
            "$bin" render --backend "$backend" --width "$w" --height "$h" --spp "$spp" --spp-per-frame "$per_frame" \
                --out "$dir/speed-$backend.exr" >"$dir/speed-$backend.log" 2>&1
            sps=$(awk -F': ' '/^samples per second/ { print $2 }' "$dir/speed-$backend.log")
            row=$(awk '/^adapter: / { sub(/^adapter: /, ""); print; exit }' "$dir/speed-$backend.log")
            printf '| native %s: %s | %.3e | %.1f |\n' "$backend" "$row" "$sps" "$(python3 -c "print($sps / $page)")"
        done
        echo
        echo "The page's figure is its frames' GPU time (submission to the queue's completion callback), so the panel's drawing is left out; the native figures are \`pathtracer render\`'s own."
    } >docs/web-speed.md
    cat docs/web-speed.md >&2
}

case "${1:-}" in
    build) build ;;
    serve) build && serve "${2:-8000}" ;;
    test) test_page ;;
    *)
        echo "usage: $0 build | serve [PORT] | test" >&2
        exit 2
        ;;
esac
