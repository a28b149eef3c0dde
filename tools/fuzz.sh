#!/usr/bin/env bash
# fuzz.sh SECONDS [extra libFuzzer flags...]
#
# Builds tests/fuzz/fuzz_gltf (libFuzzer + ASan + UBSan, clang) in build-fuzz/,
# seeds build-fuzz/corpus from tests/data/gltf (good and bad files, and the
# regression inputs), and fuzzes pf_gltf_load_memory for SECONDS seconds.
# Exits non-zero when the fuzzer finds a crash, leak or sanitizer report; the
# input is left in build-fuzz/artifacts/ (crash-*, leak-*, timeout-*, oom-*).
# A finding becomes a regression test: copy it to tests/data/gltf/regress/ and
# add a case to tests/test_gltf_loader.c.
#
# Installs nothing: it checks for clang, libFuzzer's runtime and the header-only
# dependencies and prints the apt-get line when one is missing.
# Environment: JOBS (parallel build jobs, default: nproc), FUZZ_WORKERS
# (libFuzzer -fork workers, default 1).
set -euo pipefail

usage() { echo "usage: $0 SECONDS [libFuzzer flags...]" >&2; exit 2; }
[ $# -ge 1 ] || usage
SECONDS_TO_RUN=$1
shift
case "$SECONDS_TO_RUN" in '' | *[!0-9]*) usage ;; esac

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD="$ROOT/build-fuzz"
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}
WORKERS=${FUZZ_WORKERS:-1}

# ---------------------------------------------------------------- prerequisites
missing=()
command -v clang >/dev/null 2>&1 || missing+=(clang)
command -v clang++ >/dev/null 2>&1 || missing+=(clang)
command -v cmake >/dev/null 2>&1 || missing+=(cmake)
[ -f /usr/include/nlohmann/json.hpp ] || missing+=(nlohmann-json3-dev)
[ -f /usr/include/tiny_gltf.h ] || missing+=(libtinygltf-dev)
[ -f /usr/include/stb/stb_image.h ] || missing+=(libstb-dev)
if command -v clang >/dev/null 2>&1; then
    # libFuzzer ships in compiler-rt: try linking an empty fuzz target
    probe=$(mktemp -d)
    printf '#include <stdint.h>\n#include <stddef.h>\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }\n' \
        >"$probe/p.c"
    if ! clang -fsanitize=fuzzer,address,undefined "$probe/p.c" -o "$probe/p" >/dev/null 2>&1; then
        ver=$(clang -dumpversion | cut -d. -f1)
        missing+=("libclang-rt-${ver}-dev")
    fi
    rm -rf "$probe"
fi
if [ ${#missing[@]} -gt 0 ]; then
    # shellcheck disable=SC2207
    uniq_missing=($(printf '%s\n' "${missing[@]}" | sort -u))
    echo "fuzz.sh: missing prerequisites. Install them with:" >&2
    echo "  sudo apt-get install -y ${uniq_missing[*]}" >&2
    exit 3
fi

# ---------------------------------------------------------------- build
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSOFTGI_FUZZ=ON -DSOFTGI_TESTS=OFF >/dev/null
cmake --build "$BUILD" --target fuzz_gltf -j "$JOBS"

# ---------------------------------------------------------------- corpus
# Seeds: every authored file (the fuzzer loads from memory without a base
# directory, so external .bin/.png files are just more byte strings) and every
# earlier finding. The working corpus keeps what the fuzzer adds across runs.
CORPUS="$BUILD/corpus"
ARTIFACTS="$BUILD/artifacts"
mkdir -p "$CORPUS" "$ARTIFACTS"
find "$ROOT/tests/data/gltf" -type f -exec cp -f {} "$CORPUS/" \;

# ---------------------------------------------------------------- run
echo "fuzz.sh: fuzzing for ${SECONDS_TO_RUN}s (corpus $CORPUS, findings in $ARTIFACTS)"
fork=()
[ "$WORKERS" -gt 1 ] && fork=(-fork="$WORKERS" -ignore_crashes=0)
marker="$BUILD/.fuzz_run_start"
touch "$marker"
set +e
(cd "$BUILD" && ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1} \
    UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
    ./tests/fuzz/fuzz_gltf "$CORPUS" -dict="$ROOT/tests/fuzz/gltf.dict" \
    -max_total_time="$SECONDS_TO_RUN" -max_len=65536 -rss_limit_mb=4096 -timeout=20 \
    -artifact_prefix="$ARTIFACTS/" -print_final_stats=1 "${fork[@]}" "$@")
status=$?
set -e

# only this run's findings count (older ones stay for reference)
findings=$(find "$ARTIFACTS" -type f -newer "$marker" | wc -l)
if [ "$status" -ne 0 ] || [ "$findings" -gt 0 ]; then
    echo "fuzz.sh: FAILED (exit $status); findings:" >&2
    find "$ARTIFACTS" -type f -newer "$marker" >&2
    echo "reproduce: $BUILD/tests/fuzz/fuzz_gltf FILE" >&2
    exit 1
fi
echo "fuzz.sh: no crash in ${SECONDS_TO_RUN}s"
