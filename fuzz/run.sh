#!/usr/bin/env bash
# sere fuzz — runs each libFuzzer target for a while; `make fuzz` calls this after building them.
#
#   fuzz/run.sh BUILD_DIR SECONDS TARGET...
#
# For each target: the seeds are copied afresh from data/ and tests/data/bad/ into
# BUILD_DIR/seeds/TARGET (nothing is duplicated in git), the corpus the fuzzer grows is kept in
# BUILD_DIR/corpus/TARGET between runs, and a finding is saved as BUILD_DIR/findings/TARGET-*.
# Prints libFuzzer's final stats (executions, coverage) per target; exits 1 if any target found
# something (a crash, a sanitizer report, a leak, a failed check, a timeout or out of memory).
set -uo pipefail
build=$1
seconds=$2
shift 2
cd "$(dirname "$0")/.."

seeds_of() {
	case $1 in
	fuzz_leaf) ls data/leaves/*.leaf tests/data/bad/*.leaf ;;
	fuzz_png) ls data/leaves/*.png data/masks/*.png data/masks/*.pgm tests/data/bad/*.png tests/data/bad/*.pgm ;;
	fuzz_preset) ls data/presets/*.preset tests/data/bad/*.preset ;;
	fuzz_chain) ls data/seasons/* tests/data/bad/*.chain tests/data/bad/*.schedule tests/data/bad/*.keys ;;
	fuzz_skeleton) ls data/skeletons/*.skel tests/data/bad/*.skel ;;
	esac 2>/dev/null
}

# Leaks are findings too; LLVM's OpenMP runtime and fontconfig keep caches until exit.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}

failed=()
for target in "$@"; do
	name=$(basename "$target")
	seeds=$build/seeds/$name corpus=$build/corpus/$name log=$build/logs/$name.log
	rm -rf "$seeds"
	mkdir -p "$seeds" "$corpus" "$build/findings" "$build/logs"
	seeds_of "$name" | while read -r f; do cp "$f" "$seeds/"; done
	echo "fuzz: $name for ${seconds}s ($(ls "$seeds" | wc -l) seeds, corpus $corpus, log $log)"
	# -timeout: one input taking this long is a finding (the largest image the PNG reader takes,
	# 8192 x 8192, is read in a few seconds under the sanitizers); -rss_limit_mb: such an image
	# needs about 1.5 GB.
	"$target" -max_total_time="$seconds" -print_final_stats=1 -timeout=60 -rss_limit_mb=3072 \
		-artifact_prefix="$build/findings/$name-" "$corpus" "$seeds" >"$log" 2>&1
	status=$?
	grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -n 1 | sed 's/^/  /'
	grep -E '^stat::(number_of_executed_units|average_exec_per_sec|new_units_added|peak_rss_mb)' "$log" |
		sed 's/^/  /'
	if [ $status -ne 0 ]; then
		echo "fuzz: $name FOUND SOMETHING (exit $status); the report:"
		grep -E -A40 '^==[0-9]+==ERROR|runtime error|fuzz check failed|ERROR: libFuzzer' "$log" | head -n 60
		ls "$build/findings/$name-"* 2>/dev/null | sed 's/^/  input: /'
		failed+=("$name")
	fi
done
if [ ${#failed[@]} -gt 0 ]; then
	echo "fuzz: findings in ${failed[*]}" >&2
	exit 1
fi
echo "fuzz: no findings in $# targets"
