#!/usr/bin/env bash
# Runs every libFuzzer target of leeway for a bounded time (docs/testing.md, "Fuzzing").
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [BUILD_DIR]
#
# SECONDS_PER_TARGET defaults to 60, BUILD_DIR to build-fuzz in the repository: a build configured
# with -DLEEWAY_BUILD_FUZZERS=ON -DLEEWAY_SANITIZE=address (clang), its targets built. Each target
# fuzzes a scratch copy of fuzz/corpus/NAME (the repository's corpus is never modified), with
# fuzz/regressions/NAME read as seeds too and fuzz/NAME.dict as its dictionary, one target after
# the other. Output goes to FUZZ_OUT (default BUILD_DIR/fuzz-out, emptied first): NAME.log,
# corpus/NAME (the grown corpus) and artifacts/NAME/ (reproducers). Environment: FUZZ_TARGETS
# (default "cell params bounds path urdf") picks targets, FUZZ_SEED (default 1) libFuzzer's seed.
#
# Exit status: 0 when no target found anything; 1 when one found a crash, sanitizer report, leak,
# timeout (> 10 s per input) or out-of-memory (> 2048 MB): the reproducer's path and the command
# that replays it are printed; 2 on a usage error (a missing target binary).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
build="${2:-$repo/build-fuzz}"
build="$(cd "$build" && pwd)"
out="${FUZZ_OUT:-$build/fuzz-out}"
targets="${FUZZ_TARGETS:-cell params bounds path urdf}"
# libFuzzer's random seed: fixed, so that a CI run can be repeated (FUZZ_SEED=0: a random one).
seed="${FUZZ_SEED:-1}"

if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "fuzz.sh: SECONDS_PER_TARGET '$seconds' must be a whole number >= 1" >&2
  exit 2
fi
for name in $targets; do
  if [ ! -x "$build/fuzz/leeway-fuzz-$name" ]; then
    echo "fuzz.sh: $build/fuzz/leeway-fuzz-$name is missing: configure $build with" \
      "-DLEEWAY_BUILD_FUZZERS=ON and build the target leeway-fuzz-$name" >&2
    exit 2
  fi
done

rm -rf "$out"
mkdir -p "$out"
failed=0
summary=""
for name in $targets; do
  bin="$build/fuzz/leeway-fuzz-$name"
  corpus="$out/corpus/$name"
  artifacts="$out/artifacts/$name"
  mkdir -p "$corpus" "$artifacts"
  cp -R "$repo/fuzz/corpus/$name/." "$corpus/"
  seeds=()
  [ -d "$repo/fuzz/regressions/$name" ] && seeds+=("$repo/fuzz/regressions/$name")
  dict=()
  [ -f "$repo/fuzz/$name.dict" ] && dict+=("-dict=$repo/fuzz/$name.dict")
  # A library's leak leeway cannot prevent, documented in fuzz/NAME.lsan.supp.
  lsan="${LSAN_OPTIONS:-}"
  # Last, so that it wins over a suppressions file the environment names (LeakSanitizer reads one).
  [ -f "$repo/fuzz/$name.lsan.supp" ] && lsan="${lsan:+$lsan:}suppressions=$repo/fuzz/$name.lsan.supp:print_suppressions=0"
  echo "fuzz.sh: $name for $seconds s (log: $out/$name.log)"
  status=0
  # From the scratch folder, so that nothing the target or MuJoCo writes lands in the repository.
  (cd "$out" && LSAN_OPTIONS="$lsan" "$bin" -max_total_time="$seconds" -seed="$seed" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    "${dict[@]}" -artifact_prefix="$artifacts/" "$corpus" "${seeds[@]}") >"$out/$name.log" 2>&1 || status=$?
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$out/$name.log" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$out/$name.log" | tail -1)"
  summary+="$(printf '  %-7s exit %-3s %10s runs %6s exec/s' "$name" "$status" "${execs:-?}" "${rate:-?}")"$'\n'
  if [ "$status" -ne 0 ]; then
    failed=1
    echo "fuzz.sh: $name FOUND a problem (exit $status); the end of its log:" >&2
    grep -E "^(==[0-9]+==ERROR|SUMMARY|.*runtime error|leeway fuzz:|terminate called|  what\\(\\))" \
      "$out/$name.log" | head -20 >&2 || true
    found=0
    for f in "$artifacts"/*; do
      [ -f "$f" ] || continue
      found=1
      echo "fuzz.sh:   reproducer: $f" >&2
      echo "fuzz.sh:   replay:     ${lsan:+LSAN_OPTIONS=$lsan }$bin $f" >&2
    done
    [ "$found" -eq 1 ] || tail -30 "$out/$name.log" >&2
  fi
done
echo "fuzz.sh: $seconds s per target, output in $out"
printf '%s' "$summary"
exit "$failed"
