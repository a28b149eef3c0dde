#!/usr/bin/env bash
# fuzz.sh [--smoke] SECONDS [TARGET...] [-libFuzzer-flag...]
# fuzz.sh --smoke [TARGET...]
#
# Builds the fuzz build in build-fuzz/ (clang, SOFTGI_FUZZ=ON: the whole
# library with libFuzzer coverage + ASan + UBSan, every tests/fuzz/fuzz_*.c
# and fuzz_*.cpp a target) and runs each TARGET (default: all of them) for
# SECONDS seconds. --smoke: 30 s per target (the CI smoke test; a SECONDS
# given after it overrides). TARGET is a name like fuzz_gltf or gltf.
# Arguments starting with '-' go to every libFuzzer run (e.g. -max_len=4096).
#
# Per target NAME (fuzz_NAME):
#   corpus      build-fuzz/corpus/fuzz_NAME/ (kept across runs; the fuzzer
#               adds to it), read together with the seeds, which stay
#               read-only: tests/fuzz/seeds/NAME/ and tests/fuzz/regress/NAME/
#               (earlier findings are good starting points), plus tests/data/gltf for
#               gltf, plus (for texture) the PNG and JPEG files under
#               ../shared/scenes when present, copied into
#               build-fuzz/seeds-extra/texture/, never into the repository
#   dictionary  tests/fuzz/NAME.dict (or fuzz_NAME.dict) when it exists
#   findings    build-fuzz/artifacts/fuzz_NAME/ (crash-*, leak-*, timeout-*,
#               oom-*); log in build-fuzz/logs/fuzz_NAME.log
# and it prints the executions, coverage and findings of each target.
#
# Exit status: 0 when every target ran its time and found nothing; 1 when a
# target found something in this run (older artifacts do not count), failed
# to build, or ended early (a missing target, a target that exits at once);
# 2 for bad usage; 3 for missing prerequisites (it installs nothing and
# prints the apt-get line).
#
# A finding becomes a regression test: reproduce with
#   build-fuzz/tests/fuzz/fuzz_NAME FILE
# then copy FILE to the module's test data and add a case to its test.
#
# Environment: FUZZ_BUILD (the build folder, default build-fuzz; relative
# paths are under the repository), FUZZ_JOBS (targets run in parallel, default 1), JOBS
# (parallel build jobs, default nproc), FUZZ_WORKERS (libFuzzer -fork
# workers per target, default 1), ASAN_OPTIONS / UBSAN_OPTIONS (override the
# defaults below).
set -euo pipefail

usage() {
    echo "usage: $0 [--smoke] SECONDS [TARGET...] [-libFuzzer-flag...]" >&2
    echo "       $0 --smoke [TARGET...]          (30 s per target)" >&2
    exit 2
}
is_number() { case "$1" in '' | *[!0-9]*) return 1 ;; *) return 0 ;; esac; }

SMOKE=0
SECONDS_TO_RUN=""
if [ "${1:-}" = "--smoke" ]; then
    SMOKE=1
    SECONDS_TO_RUN=30
    shift
    if [ $# -gt 0 ] && is_number "$1"; then SECONDS_TO_RUN=$1; shift; fi
else
    # shellcheck disable=SC2015
    [ $# -ge 1 ] && is_number "$1" || usage
    SECONDS_TO_RUN=$1
    shift
fi
[ "$SECONDS_TO_RUN" -ge 1 ] || usage
WANTED=()
EXTRA=()
for a in "$@"; do
    case "$a" in
    -*) EXTRA+=("$a") ;;
    *) WANTED+=("$a") ;;
    esac
done

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${FUZZ_BUILD:-build-fuzz}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}
PAR=${FUZZ_JOBS:-1}
WORKERS=${FUZZ_WORKERS:-1}
# shellcheck disable=SC2015
is_number "$PAR" && [ "$PAR" -ge 1 ] || { echo "fuzz.sh: FUZZ_JOBS must be a positive integer" >&2; exit 2; }
# shellcheck disable=SC2015
is_number "$WORKERS" && [ "$WORKERS" -ge 1 ] || { echo "fuzz.sh: FUZZ_WORKERS must be a positive integer" >&2; exit 2; }

# ---------------------------------------------------------------- prerequisites
missing=()
command -v clang >/dev/null 2>&1 || missing+=(clang)
command -v clang++ >/dev/null 2>&1 || missing+=(clang)
command -v cmake >/dev/null 2>&1 || missing+=(cmake)
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
[ -f /usr/include/nlohmann/json.hpp ] || missing+=(nlohmann-json3-dev)
[ -f /usr/include/tiny_gltf.h ] || missing+=(libtinygltf-dev)
[ -f /usr/include/stb/stb_image.h ] || missing+=(libstb-dev)
[ -f /usr/include/tinyexr.h ] || missing+=(libtinyexr-dev) # compiled into the fuzz build (fuzz_exr)
[ -f /usr/include/zlib.h ] || missing+=(zlib1g-dev)
if command -v pkg-config >/dev/null 2>&1; then
    pkg-config --exists spng || missing+=(libspng-dev)
    pkg-config --exists libturbojpeg || missing+=(libturbojpeg0-dev)
fi
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
    echo "(the other build dependencies: tools/install-deps.sh)" >&2
    exit 3
fi

# ---------------------------------------------------------------- targets
ALL=()
for f in "$ROOT"/tests/fuzz/fuzz_*.c "$ROOT"/tests/fuzz/fuzz_*.cpp; do
    [ -e "$f" ] || continue
    n=$(basename "$f")
    ALL+=("${n%.*}")
done
# shellcheck disable=SC2207
ALL=($(printf '%s\n' "${ALL[@]}" | sort -u))
TARGETS=()
MISSING=()
status=0
if [ ${#WANTED[@]} -eq 0 ]; then
    TARGETS=("${ALL[@]}")
else
    for w in "${WANTED[@]}"; do
        t=fuzz_${w#fuzz_}
        if printf '%s\n' "${ALL[@]}" | grep -qx "$t"; then
            TARGETS+=("$t")
        else
            echo "fuzz.sh: ERROR: no fuzz target '$w' (tests/fuzz/$t.c or .cpp); targets: ${ALL[*]}" >&2
            MISSING+=("$t")
            status=1
        fi
    done
fi
[ ${#TARGETS[@]} -gt 0 ] || { echo "fuzz.sh: no target to run" >&2; exit 1; }

# ---------------------------------------------------------------- build
# Debug: asserts stay on (the hot loops' only checks); the fuzz flags add -O1.
echo "fuzz.sh: configuring and building ${TARGETS[*]} in $BUILD (-j$JOBS)"
mkdir -p "$BUILD/logs"
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Debug \
    -DSOFTGI_FUZZ=ON -DSOFTGI_TESTS=OFF >"$BUILD/logs/configure.log" 2>&1 ||
    { cat "$BUILD/logs/configure.log" >&2; echo "fuzz.sh: cmake configure failed" >&2; exit 1; }
cmake --build "$BUILD" --target softgi_core -j "$JOBS" >"$BUILD/logs/build-softgi_core.log" 2>&1 ||
    { tail -n 40 "$BUILD/logs/build-softgi_core.log" >&2; echo "fuzz.sh: building softgi_core failed" >&2; exit 1; }
BUILT=()
declare -A RESULT
for t in "${TARGETS[@]}"; do
    if cmake --build "$BUILD" --target "$t" -j "$JOBS" >"$BUILD/logs/build-$t.log" 2>&1; then
        BUILT+=("$t")
    else
        tail -n 30 "$BUILD/logs/build-$t.log" >&2
        echo "fuzz.sh: ERROR: $t failed to build (log: $BUILD/logs/build-$t.log)" >&2
        RESULT[$t]="BUILD FAILED"
        status=1
    fi
done

# ---------------------------------------------------------------- run
# The last number printed after LABEL in FILE (empty if none).
last_number() { { grep -o "$1 *[0-9][0-9]*" "$2" || true; } | tail -n1 | grep -o '[0-9]*$' || true; }

# Runs one target; its summary goes to $BUILD/logs/TARGET.summary.
run_target() {
    set +e # best effort from here: the verdict below is explicit (this runs in its own subshell)
    local t=$1 name=${1#fuzz_}
    local bin="$BUILD/tests/fuzz/$t" corpus="$BUILD/corpus/$t" art="$BUILD/artifacts/$t"
    local log="$BUILD/logs/$t.log" sum="$BUILD/logs/$t.summary"
    rm -f "$sum"
    mkdir -p "$corpus" "$art"
    local dirs=("$corpus")
    [ -d "$ROOT/tests/fuzz/seeds/$name" ] && dirs+=("$ROOT/tests/fuzz/seeds/$name")
    [ -d "$ROOT/tests/fuzz/regress/$name" ] && dirs+=("$ROOT/tests/fuzz/regress/$name")
    [ "$name" = gltf ] && [ -d "$ROOT/tests/data/gltf" ] && dirs+=("$ROOT/tests/data/gltf")
    if [ "$name" = texture ] && [ -d "$ROOT/../shared/scenes" ]; then
        # real textures, at most 64 of at most 1 MiB, smallest first: copies in the build folder only
        local extra="$BUILD/seeds-extra/texture"
        rm -rf "$extra"
        mkdir -p "$extra"
        find "$ROOT/../shared/scenes" -type f \( -iname '*.png' -o -iname '*.jpg' -o -iname '*.jpeg' \) \
            -size -1025k -printf '%s %p\n' 2>/dev/null | sort -n | head -n 64 | cut -d' ' -f2- |
            while IFS= read -r f; do cp -f "$f" "$extra/$(printf '%s' "$f" | md5sum | cut -c1-12)-$(basename "$f")"; done
        dirs+=("$extra")
    fi
    local opts=(-max_total_time="$SECONDS_TO_RUN" -timeout=20 -rss_limit_mb=4096 -print_final_stats=1
        -artifact_prefix="$art/")
    [ "$name" = gltf ] && opts+=(-max_len=65536)
    local d
    for d in "$ROOT/tests/fuzz/$name.dict" "$ROOT/tests/fuzz/$t.dict"; do
        [ -f "$d" ] && opts+=(-dict="$d") && break
    done
    [ "$WORKERS" -gt 1 ] && opts+=(-fork="$WORKERS" -ignore_crashes=0)
    local marker="$BUILD/logs/$t.start"
    touch "$marker"
    sleep 1 # artifacts of this run are strictly newer than the marker
    local start end rc
    start=$(date +%s)
    (cd "$BUILD" && ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1} \
        UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
        "$bin" "${opts[@]}" "${EXTRA[@]}" "${dirs[@]}") >"$log" 2>&1
    rc=$?
    end=$(date +%s)
    local elapsed=$((end - start))
    # what libFuzzer printed: "stat::number_of_executed_units: N", "#N ... cov: C ft: F corp: K/..."
    local execs cov ft corp rate
    execs=$(last_number 'stat::number_of_executed_units:' "$log")
    cov=$(last_number 'cov:' "$log")
    ft=$(last_number 'ft:' "$log")
    corp=$(last_number 'corp:' "$log")
    rate=$(last_number 'stat::average_exec_per_sec:' "$log")
    local findings
    findings=$(find "$art" -type f -newer "$marker" \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' \
        -o -name 'oom-*' -o -name 'deadly-*' \) | sort)
    local slow
    slow=$(find "$art" -type f -newer "$marker" -name 'slow-unit-*' | wc -l)
    local verdict=ok
    if [ -n "$findings" ]; then
        verdict=FOUND
    elif [ $rc -ne 0 ]; then
        verdict="FAILED (exit $rc, no artifact; see $log)"
    elif ! grep -q 'Done [0-9]* runs in' "$log" || [ $((elapsed + 3)) -lt "$SECONDS_TO_RUN" ]; then
        verdict="ENDED EARLY after ${elapsed}s (see $log)"
    fi
    {
        printf '%s: %s; %s execs (%s/s), cov %s, ft %s, corpus %s, %ss, findings %d' "$t" "$verdict" \
            "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$elapsed" \
            "$(printf '%s' "$findings" | grep -c . || true)"
        if [ "$slow" -gt 0 ]; then printf ' (+%d slow-unit notes)' "$slow"; fi
        printf '\n'
        local f
        for f in $findings; do
            printf '    %s\n' "$f"
            # the first report line of the finding, for the reader
            grep -m1 -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error|PATH TRAVERSAL|invariant failed|fuzz_[a-z]*: ' \
                "$log" | sed 's/^/      /' | cut -c1-240
        done
        if [ -n "$findings" ]; then printf '    reproduce: %s FILE\n' "$bin"; fi
    } >"$sum"
    [ "$verdict" = ok ]
}

echo "fuzz.sh: ${SECONDS_TO_RUN}s per target, ${PAR} at a time: ${BUILT[*]:-none}"
pids=()
for t in "${BUILT[@]}"; do
    while [ "$(jobs -rp | wc -l)" -ge "$PAR" ]; do sleep 1; done
    echo "fuzz.sh: running $t (log: $BUILD/logs/$t.log)"
    run_target "$t" &
    pids+=($!)
done
for p in "${pids[@]}"; do wait "$p" || status=1; done

# ---------------------------------------------------------------- report
echo
echo "fuzz.sh: summary (${SECONDS_TO_RUN}s per target$([ $SMOKE = 1 ] && echo ', smoke'))"
for t in "${MISSING[@]}"; do echo "$t: NO SUCH TARGET"; done
for t in "${TARGETS[@]}"; do
    if [ -n "${RESULT[$t]:-}" ]; then
        echo "$t: ${RESULT[$t]}"
    elif [ -f "$BUILD/logs/$t.summary" ]; then
        cat "$BUILD/logs/$t.summary"
    fi
done
if [ $status -ne 0 ]; then
    echo "fuzz.sh: FAILED (findings are in $BUILD/artifacts/TARGET/, logs in $BUILD/logs/)" >&2
    exit 1
fi
echo "fuzz.sh: no findings"
