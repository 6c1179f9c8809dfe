#!/usr/bin/env bash
# The layer check (tests/lint/layers.pl) fails where it must: on a copy of the tree it passes as
# it is, then fails on each planted fault, naming the file, the line and the rule:
#   - a wrong-way include (core/base includes a family's internal header),
#   - one front end including the other (the runner includes the OpenFX adapter),
#   - the graph engine including the runner, and the image I/O library or the runner including
#     the engine's internals (only nprfx/graph.h, and engine_util.h's clocks, are for others),
#   - a loop between two files of one folder,
#   - an include that resolves to no file.
set -u
SRC=$1; W=$2
rm -rf "$W"; mkdir -p "$W"
fails=0; passes=0
check() { # check NAME EXPECTED_STATUS EXPECTED_TEXT
    local out status
    out=$(perl "$SRC/tests/lint/layers.pl" "$W/tree" 2>&1); status=$?
    if [ "$status" -ne "$2" ] || ! grep -qF -- "$3" <<<"$out"; then
        echo "FAIL: $1: exit $status (expected $2), output:"; echo "$out"; echo "(expected: $3)"
        fails=$((fails + 1))
    else
        passes=$((passes + 1))
    fi
}
fresh() {
    rm -rf "$W/tree"; mkdir -p "$W/tree"
    cp -r "$SRC/include" "$SRC/core" "$SRC/plugins" "$SRC/engine" "$SRC/io" "$SRC/common" "$SRC/cli" \
          "$W/tree/"
}
plant() { # plant FILE LINE: append an #include line
    printf '%s\n' "$2" >>"$W/tree/$1"
}

fresh
check "the tree as it is" 0 "layers ok:"

fresh
plant core/base/exec.c '#include "gabor/internal_gabor.h"'
check "wrong-way include" 1 "core/base/exec.c:$(wc -l <"$W/tree/core/base/exec.c"): includes core/gabor/internal_gabor.h: layer 'base' may not include layer 'gabor'"

fresh
main=$(cd "$W/tree" && ls cli/main.c)
plant "$main" '#include "ofx/ofx_api.h"'
check "front end into front end" 1 "includes plugins/ofx/ofx_api.h: layer 'cli' may not include layer 'ofx'"

fresh
plant engine/graph_eval.c '#include "commands/commands.h"'
check "engine includes the runner" 1 "engine/graph_eval.c:$(wc -l <"$W/tree/engine/graph_eval.c"): includes cli/commands/commands.h: layer 'engine' may not include layer 'cli/commands'"

fresh
plant cli/host/host_project.c '#include "engine/graph_model.h"'
check "front end includes the engine's internals" 1 "cli/host/host_project.c:$(wc -l <"$W/tree/cli/host/host_project.c"): includes engine/graph_model.h: layer 'cli/host' may not include layer 'engine'"

fresh
plant io/io_parts.h '#include "engine/graph_model.h"'
check "I/O library includes the engine's internals" 1 "io/io_parts.h:$(wc -l <"$W/tree/io/io_parts.h"): includes engine/graph_model.h: layer 'io' may not include layer 'engine'"

fresh
plant core/base/internal_simd.h '#include "internal_state.h"'
plant core/base/internal_state.h '#include "internal_simd.h"'
check "loop between files" 1 "loop between files: core/base/internal_simd -> core/base/internal_state -> core/base/internal_simd"

fresh
plant core/looks/blend.c '#include "internal_gone.h"'
check "stale include" 1 "core/looks/blend.c:$(wc -l <"$W/tree/core/looks/blend.c"): #include \"internal_gone.h\" is no file of the tree"

echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
