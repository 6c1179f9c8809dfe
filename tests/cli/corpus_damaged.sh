#!/usr/bin/env bash
# Damaged EXRs are refused quickly, in bounded memory, with a message naming the file, and never
# read into garbage. The corpus is generated here from valid EXRs the generator writes
# itself (tests/data/make_damaged.c, plus a mipmapped one from oiiotool); the fuzzers' findings in
# tests/data/regressions/read/ are replayed with it.
#
# Two passes:
#   1. every file through `nprfx info --io-test damaged` (one process; a refusal takes about a
#      millisecond, loading the runner half a second): each file's info + read must take under
#      2 s, the process's peak memory must stay under 512 MiB, a "must-*" file must be refused, a
#      refusal must name the file, and a file read must have printable, unique channel names;
#   2. a sample of the worst files through the plain CLI, one process each: no signal, exit
#      status 4, the file named on stderr, peak RSS under 512 MiB, and under 2 s beyond the
#      time the same command takes on a valid file (the runner's start-up).
# Under the sanitizers (NPRFX_SANITIZE=ON) CMake sets NPRFX_TEST_TIME_SCALE=5 and the memory
# bound grows by ASan's shadow and quarantine (NPRFX_TEST_MEM_MIB, default 512; 2048 there).
set -u
NPRFX=$1
SRC=$2
WORK=$3
GEN=${NPRFX_MAKE_DAMAGED:-$(dirname "$NPRFX")/tests/nprfx_make_damaged}
SCALE=${NPRFX_TEST_TIME_SCALE:-1}
MEM_MIB=${NPRFX_TEST_MEM_MIB:-512}
if [ "$SCALE" != 1 ] && [ -z "${NPRFX_TEST_MEM_MIB:-}" ]; then MEM_MIB=2048; fi
# The memory limit's default is half the physical memory: pinned here, so that the
# 12 GiB window below is refused before a read on any machine, as it was with the old 4 GiB.
export NPRFX_READ_LIMIT=${NPRFX_READ_LIMIT:-4G}
TIME_BOUND=$(awk -v s="$SCALE" 'BEGIN { print 2 * s }')
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1
fail=0
bad() {
    echo "FAIL: $*"
    fail=1
}

# ---- the corpus ----------------------------------------------------------------------------
extra=()
if command -v oiiotool >/dev/null; then
    oiiotool --pattern checker:width=4:height=4 45x37 3 -d half -otex mip.exr 2>/dev/null &&
        extra+=("$WORK/mip.exr")
fi
"$GEN" corpus "${extra[@]}" >gen.log 2>&1 || {
    cat gen.log
    bad "the generator failed"
    exit 1
}
# The valid bases go first: each must be read (pass 1 checks it), or the corpus proves nothing.
printf '%s\n' corpus/base/*.exr "${extra[@]}" >list.txt
nbases=$(wc -l <list.txt)
find corpus/damaged -type f -name '*.exr' | sort >>list.txt
ndamaged=$(($(wc -l <list.txt) - nbases))
[ "$ndamaged" -ge 1000 ] || bad "only $ndamaged damaged files were generated"
# The fuzzers' findings: each must now be refused or read cleanly, like an "any" file.
if [ -d "$SRC/tests/data/regressions/read" ]; then
    find "$SRC/tests/data/regressions/read" -type f ! -name '*.md' | sort >>list.txt
fi
echo "corpus: $nbases valid bases, $ndamaged damaged files, $(($(wc -l <list.txt) - ndamaged - nbases)) regressions"

# ---- pass 1: every file, one process ---------------------------------------------------------
start=$(date +%s.%N)
"$NPRFX" info --io-test damaged list.txt >verdicts.tsv 2>pass1.err
rc=$?
end=$(date +%s.%N)
if [ $rc -ge 128 ]; then
    bad "pass 1 died with signal $((rc - 128)) after $(wc -l <verdicts.tsv) files; last: $(tail -1 verdicts.tsv | cut -f4)"
elif [ $rc -ne 0 ]; then
    bad "pass 1 exited $rc: $(head -3 pass1.err)"
fi
nverdicts=$(wc -l <verdicts.tsv)
[ "$nverdicts" -eq "$(wc -l <list.txt)" ] || bad "pass 1 gave $nverdicts verdicts for $(wc -l <list.txt) files"
awk -F'\t' -v tb="$TIME_BOUND" -v mb="$MEM_MIB" -v nb="$nbases" '
    { base = $4; sub(/.*\//, "", base) }
    NR <= nb && $1 != "read" { print "FAIL: valid base " $4 " was not read: " $5; f = 1 }
    NR <= nb { next }
    $1 == "garbage" { print "FAIL: " $4 " read with " $5; f = 1 }
    $1 == "unnamed" { print "FAIL: " $4 ": the message does not name the file: " $5; f = 1 }
    $1 == "read" && base ~ /^must-/ { print "FAIL: " $4 " was read (" $5 "); it must be refused"; f = 1 }
    $2 + 0 > tb { print "FAIL: " $4 " took " $2 " s (bound " tb " s): " $5; f = 1 }
    $3 + 0 > mb { print "FAIL: peak memory reached " $3 " MiB (bound " mb ") at " $4; f = 1; exit }
    { n[$1]++; if ($2 > worst) { worst = $2; wf = $4 } }
    END {
        printf "pass 1: %d refused, %d read cleanly, %d refused by read only (info passes);", n["refused"], n["read"], n["mixed"]
        printf " slowest %.3f s (%s)\n", worst, wf
        exit f
    }' verdicts.tsv || fail=1
echo "pass 1: $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s for $nverdicts files, peak $(tail -1 verdicts.tsv | cut -f3) MiB"

# ---- pass 2: the CLI on a sample, one process each -------------------------------------------
measure() { # FILE -> "rc seconds maxrss_kib" (rc as bash sees it: 128+N for signal N)
    /usr/bin/time -f "%e %M" -o time.txt "$NPRFX" info --io-test channel "$1" R >out.txt 2>err.txt
    echo "$? $(cat time.txt | tail -1)"
}
read -r _ base_s _ <<<"$(measure corpus/base/scan_zip_half.exr)"
cli_bound=$(awk -v b="$base_s" -v t="$TIME_BOUND" 'BEGIN { print b + t }')
sample=(
    corpus/damaged/must-crafted-memory-dos-12gib-window.exr
    corpus/damaged/must-crafted-ratio-122mib-from-64-bytes.exr
    corpus/damaged/must-crafted-channels-100000.exr
    corpus/damaged/must-crafted-name-control.exr
    corpus/damaged/must-scan_zip_half-p0-data-window-100000x100000.exr
    corpus/damaged/must-tile_zip_half-tiles-2147483647x2147483647.exr
    corpus/damaged/any-tile_zip_half-flipff-at-402.exr
    corpus/damaged/must-multipart_zip_rle-truncated-at-103.exr
)
# The slowest refusals of pass 1 too.
while IFS= read -r f; do sample+=("$f"); done < <(awk -F'\t' '$1 != "read"' verdicts.tsv | sort -t$'\t' -k2 -g -r | head -1 | cut -f4)
for f in "${sample[@]}"; do
    [ -f "$f" ] || {
        bad "sample file $f is missing from the corpus"
        continue
    }
    read -r rc secs kib <<<"$(measure "$f")"
    if [ "$rc" -ge 128 ]; then
        bad "$f: killed by signal $((rc - 128))"
    elif [ "$rc" -eq 0 ]; then
        case "$(basename "$f")" in must-*) bad "$f was read; it must be refused" ;; esac
    elif [ "$rc" -ne 4 ]; then
        bad "$f: exit status $rc, expected 4 (file error)"
    elif ! grep -qF "$f" err.txt; then
        bad "$f: the message does not name the file: $(head -1 err.txt)"
    fi
    awk -v s="$secs" -v b="$cli_bound" 'BEGIN { exit !(s > b) }' && bad "$f: $secs s (bound $cli_bound s)"
    [ "$((kib / 1024))" -le "$MEM_MIB" ] || bad "$f: $((kib / 1024)) MiB (bound $MEM_MIB)"
    printf '  %-70s rc %s  %5.2f s  %4d MiB\n' "$(basename "$f")" "$rc" "$secs" "$((kib / 1024))"
done

# ---- the bounds themselves --------------------------------------------------------------------
# The messages name the size and the limit, and the limit follows NPRFX_READ_LIMIT.
grep -F "must-crafted-memory-dos-12gib-window.exr': data window 200000000x16 with 1 channel needs 11.9 GiB, above the" verdicts.tsv |
    grep -q "above the 4 GiB memory limit (NPRFX_READ_LIMIT)" || bad "the memory-limit message is not as expected: $(grep memory-dos-12gib verdicts.tsv)"
NPRFX_READ_LIMIT=1K "$NPRFX" info --io-test channel corpus/base/scan_zip_half.exr R 2>err.txt >/dev/null &&
    bad "a 37x41 plate was read under NPRFX_READ_LIMIT=1K"
grep -q "needs 23.7 KiB, above the 1 KiB memory limit (NPRFX_READ_LIMIT)" err.txt || bad "NPRFX_READ_LIMIT=1K: $(cat err.txt)"
NPRFX_READ_LIMIT=lots "$NPRFX" info --io-test channel corpus/base/scan_zip_half.exr R 2>err.txt >/dev/null &&
    bad "a malformed NPRFX_READ_LIMIT was accepted"
grep -q "NPRFX_READ_LIMIT='lots' is not a size" err.txt || bad "NPRFX_READ_LIMIT=lots: $(cat err.txt)"
# The time bound: a read given no time at all is stopped with a message naming the file.
NPRFX_READ_TIMEOUT=0.000001 "$NPRFX" info --io-test channel corpus/base/scan_zip_half.exr R 2>err.txt >/dev/null &&
    bad "a read went on past NPRFX_READ_TIMEOUT"
grep -q "'corpus/base/scan_zip_half.exr': reading took longer than 1e-06 s" err.txt || bad "NPRFX_READ_TIMEOUT: $(cat err.txt)"

[ $fail -eq 0 ] && echo "corpus_damaged: all checks passed"
exit $fail
