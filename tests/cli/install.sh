#!/usr/bin/env bash
# The installed library is usable: `cmake --install` of the build tree into a prefix gives
# libnprfx (shared with its SONAME links, and static), the public headers and no internal one,
# nprfx.pc and the CMake package; samples/example/render_node.c then builds and runs against it
# through pkg-config (shared and --static) and through find_package(nprfx) (nprfx::nprfx and
# nprfx::nprfx_static), and libnprfx.so exports exactly the functions the headers declare with
# NPRFX_API, no internal_ symbol. The install is staged with DESTDIR and moved into the prefix,
# so destinations outside the prefix (the OpenFX bundle's /usr/OFX/Plugins) stay off the system.
#
# usage: bash install.sh NPRFX_BINARY SOURCE_DIR WORK_DIR   (the build tree is NPRFX's folder)
set -u
NPRFX=$1; SRC=$2; W=$3
BUILD=$(cd "$(dirname "$NPRFX")" && pwd)
rm -rf "$W"; mkdir -p "$W"; cd "$W"; W=$(pwd)
P=$W/prefix
passes=0; fails=0
pass() { passes=$((passes+1)); }
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
finish() { echo "$passes passed, $fails failed"; [ $fails -eq 0 ] && [ $passes -gt 0 ]; exit; }
check() { # DESCRIPTION CMD...: CMD must succeed; its output goes to last.log
  local what=$1; shift
  if "$@" > last.log 2>&1; then pass; else fail "$what: '$*':"; tail -n 30 last.log; fi
}
cache() { sed -n "s/^$1:[A-Z]*=//p" "$BUILD/CMakeCache.txt"; }

[ -f "$BUILD/CMakeCache.txt" ] || { fail "no CMakeCache.txt beside $NPRFX"; finish; }
CC=$(cache CMAKE_C_COMPILER); CC=${CC:-cc}
SAN=()
[ "$(cache NPRFX_SANITIZE)" = ON ] && SAN=(-fsanitize=address,undefined)

# ---- install ---------------------------------------------------------------------------------
if DESTDIR=$W/stage cmake --install "$BUILD" --prefix "$P" > install.log 2>&1 &&
   [ -d "$W/stage$P" ] && mv "$W/stage$P" "$P"; then pass
else fail "cmake --install $BUILD --prefix $P:"; tail -n 30 install.log; finish; fi

pc=$(find "$P" -name nprfx.pc | head -n 1)
[ -n "$pc" ] && pass || { fail "no nprfx.pc installed"; finish; }
LIB=$(dirname "$(dirname "$pc")")
export PKG_CONFIG_PATH=$LIB/pkgconfig
for f in bin/nprfx share/nprfx/ivs.bin include/nprfx/nprfx.h include/nprfx/export.h; do
  [ -s "$P/$f" ] && pass || fail "$f is not installed"
done
for f in libnprfx.a cmake/nprfx/nprfxConfig.cmake cmake/nprfx/nprfxConfigVersion.cmake \
         cmake/nprfx/nprfxTargets.cmake; do
  [ -s "$LIB/$f" ] && pass || fail "$LIB/$f is not installed"
done
[ -n "$(find "$W/stage" -path '*nprfx.ofx.bundle/Contents/*/nprfx.ofx' 2>/dev/null)$(find "$P" -path '*nprfx.ofx.bundle/Contents/*/nprfx.ofx')" ] &&
  pass || fail "the OpenFX bundle is not installed"
# public headers: exactly those of include/nprfx, no internal_*.h
(cd "$SRC/include/nprfx" && ls) > want.txt; (cd "$P/include/nprfx" && ls) > got.txt
cmp -s want.txt got.txt && pass || { fail "installed headers differ from include/nprfx:"; diff want.txt got.txt; }
[ -z "$(find "$P" -name 'internal_*')" ] && pass || fail "internal headers installed: $(find "$P" -name 'internal_*')"

# libnprfx.so -> libnprfx.so.SONAME -> the file; the SONAME link resolves
so=$LIB/libnprfx.so
soname=$(readelf -d "$so" 2>/dev/null | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
[ -L "$so" ] && [ -n "$soname" ] && [ -L "$LIB/$soname" ] && [ -f "$LIB/$soname" ] && pass ||
  fail "libnprfx.so: no symlink chain to its SONAME '$soname'"

# ---- exported symbols: the NPRFX_API declarations, nothing else ------------------------------
nm -D --defined-only "$so" | awk '$2 ~ /^[TDBRVW]$/ {print $3}' | sort > exported.txt
grep -v '^nprfx_' exported.txt > stray.txt
[ -s exported.txt ] && [ ! -s stray.txt ] && pass || { fail "libnprfx.so exports non-API symbols:"; head stray.txt; }
! grep -q internal_ exported.txt && pass || fail "libnprfx.so exports internal_ symbols"
ls "$P"/include/nprfx/*.h | grep -v '/export\.h$' | xargs cat | tr '\n' ' ' |
  grep -oE 'NPRFX_API[^;(]*\(' | grep -oE 'nprfx_[A-Za-z0-9_]+ *\($' | tr -d ' (' | sort -u > declared.txt
[ -s declared.txt ] && cmp -s declared.txt exported.txt && pass ||
  { fail "declared (NPRFX_API) and exported functions differ (< declared, > exported):"; diff declared.txt exported.txt | head; }

# ---- pkg-config ------------------------------------------------------------------------------
version=$(sed -n 's/^#define NPRFX_VERSION_STRING "\(.*\)"/\1/p' "$P/include/nprfx/nprfx.h")
[ "$(pkg-config --modversion nprfx 2>&1)" = "$version" ] && pass ||
  fail "pkg-config --modversion nprfx: '$(pkg-config --modversion nprfx 2>&1)', want '$version'"
has_words() { # WORDS TEXT: every word of WORDS is a word of TEXT
  local w; for w in $1; do case " $2 " in *" $w "*) ;; *) return 1 ;; esac; done
}
flags=$(pkg-config --cflags --libs nprfx 2>&1)
has_words "-I$P/include -L$LIB -lnprfx" "$flags" && pass || fail "pkg-config --cflags --libs: $flags"
static_libs=$(pkg-config --static --libs nprfx 2>&1)
has_words "-lnprfx -lpthread -lm" "$static_libs" && pass || fail "pkg-config --static --libs: $static_libs"

# ---- the example, three ways -----------------------------------------------------------------
EX=$SRC/samples/example/render_node.c
run_example() { # NAME [env...] BINARY: it exits 0 and ends with "ok"
  local name=$1; shift
  if env "$@" > "$name.out" 2>&1 && [ "$(tail -n 1 "$name.out")" = ok ]; then pass
  else fail "$name:"; cat "$name.out"; fi
}
# shared, through pkg-config
check "build the example (shared)" "$CC" -std=c11 -Wall -Wextra -Werror "${SAN[@]}" "$EX" -o ex_shared \
  $(pkg-config --cflags --libs nprfx)
readelf -d ex_shared 2>/dev/null | grep -q "NEEDED.*\[$soname\]" && pass || fail "ex_shared does not load $soname"
run_example shared LD_LIBRARY_PATH="$LIB" ./ex_shared
# static, through pkg-config --static: libnprfx.a by name (-lnprfx would pick the .so)
check "build the example (static)" "$CC" -std=c11 -Wall -Wextra -Werror "${SAN[@]}" "$EX" -o ex_static \
  $(pkg-config --cflags nprfx) $(pkg-config --static --libs nprfx | sed 's/-lnprfx\b/-l:libnprfx.a/')
! readelf -d ex_static 2>/dev/null | grep -q "NEEDED.*libnprfx" && pass || fail "ex_static loads libnprfx.so"
run_example static ./ex_static
cmp -s shared.out static.out && pass || { fail "shared and static examples differ:"; diff shared.out static.out; }
# CMake: find_package(nprfx), the shared target (samples/example/CMakeLists.txt) and the static one
mkdir -p cmake-static
sed 's/nprfx::nprfx)/nprfx::nprfx_static)/; s|render_node.c|'"$EX"'|' \
  "$SRC/samples/example/CMakeLists.txt" > cmake-static/CMakeLists.txt
for v in shared static; do
  if [ $v = shared ]; then dir=$SRC/samples/example; else dir=$W/cmake-static; fi
  check "configure the example's CMake project ($v)" cmake -S "$dir" -B "cmake-$v-build" \
    -DCMAKE_PREFIX_PATH="$P" -DCMAKE_C_COMPILER="$CC" -DCMAKE_C_FLAGS="${SAN[*]}" -DCMAKE_BUILD_TYPE=Release
  check "build the example's CMake project ($v)" cmake --build "cmake-$v-build"
  run_example cmake-$v "cmake-$v-build/render_node"
  cmp -s shared.out cmake-$v.out && pass || fail "the CMake-built example ($v) prints otherwise"
done
! readelf -d cmake-static-build/render_node 2>/dev/null | grep -q "NEEDED.*libnprfx" && pass ||
  fail "nprfx::nprfx_static links libnprfx.so"

# ---- libnprfx-io and the graph engine -----------------------------------------------------------
# nprfx-io.pc (requiring nprfx) and libnprfx-io.so, which exports only nprfx/io_oiio.h's
# functions; samples/example/run_graph.c runs a sample graph through the installed engine and
# writes what `nprfx run` writes, pixel for pixel.
iolib=$LIB/libnprfx-io.so
[ -L "$iolib" ] && [ -s "$LIB/pkgconfig/nprfx-io.pc" ] && pass || fail "libnprfx-io.so or nprfx-io.pc is not installed"
nm -D --defined-only "$iolib" | awk '$2 ~ /^[TDBRVW]$/ {print $3}' | sort > io_exported.txt
tr '\n' ' ' < "$P/include/nprfx/io_oiio.h" | grep -oE 'NPRFX_IO_API[^;(]*\(' |
  grep -oE 'nprfx_[A-Za-z0-9_]+ *\($' | tr -d ' (' | sort -u > io_declared.txt
[ -s io_declared.txt ] && cmp -s io_declared.txt io_exported.txt && pass ||
  { fail "libnprfx-io: declared (NPRFX_IO_API) and exported differ:"; diff io_declared.txt io_exported.txt | head; }
check "build run_graph.c (shared)" "$CC" -std=c11 -Wall -Wextra -Werror "${SAN[@]}" \
  "$SRC/samples/example/run_graph.c" -o run_graph $(pkg-config --cflags --libs nprfx-io)
if LD_LIBRARY_PATH="$LIB" ./run_graph "$SRC/samples/graphs/toon.json" eng 1-2 > run_graph.out 2>&1 &&
   [ "$(tail -n 1 run_graph.out)" = ok ]; then pass; else fail "run_graph:"; cat run_graph.out; fi
grep -q "^frame 2 (2/2): done" run_graph.out && grep -q "calls*$" run_graph.out && pass ||
  fail "run_graph: no progress or statistics lines"
"$NPRFX" run "$SRC/samples/graphs/toon.json" --frames 1-2 --output-dir cli --quiet > cli.log 2>&1 ||
  fail "nprfx run toon.json: $(cat cli.log)"
n=0
for f in $(cd cli && find . -name '*.exr' | sort); do
  n=$((n+1))
  "$NPRFX" diff "cli/$f" "eng/$f" --fail 0 > /dev/null 2>&1 || fail "run_graph and nprfx run differ on $f"
done
[ "$n" -gt 0 ] && pass || fail "nprfx run toon.json wrote no EXR"

# ---- the installed runner ----------------------------------------------------------------------
check "the installed runner lists threshold-map" sh -c "'$P/bin/nprfx' list | grep -q threshold-map"

# ---- the Python module, where the prefix's interpreter looks (when the build has it) -----------
# the interpreter the build found (FindPython keeps it in an internal cache entry)
PY=$(cache _Python3_EXECUTABLE); [ -n "$PY" ] || PY=$(cache Python3_EXECUTABLE); PY=${PY:-python3}
if [ -n "$(find "$BUILD/python" -name 'nprfx*.so' 2>/dev/null)" ]; then
  mod=$(find "$P/lib" -path '*/python3.*/*-packages/nprfx*.so' | head -n 1)
  [ -n "$mod" ] && pass || fail "the Python module was not installed under $P/lib/python3.X"
  [ -n "$mod" ] && check "the installed Python module imports and lists the nodes" \
    env PYTHONPATH="$(dirname "$mod")" "$PY" -c 'import nprfx; assert "threshold-map" in nprfx.nodes()'
fi

finish
