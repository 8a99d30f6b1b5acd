#!/bin/bash
# ctest CacheFilesCli (docs/reliability.md "Files"): canopy-layers, canopy-demo --gltf and
# canopy-demo --impostors far --gltf against a hostile model folder and cache folder. Links at every
# cache's final and temporary names (the linked file must stay unchanged), FIFOs (each program
# finishes within 3x its time without caches, at least 10 s), folders at the cache names, a read-only model folder (nothing written
# there), a full disk (a small tmpfs, and an injected file-size limit), truncated / bit-flipped /
# oversized caches (rebuilt, saying why), two processes at once, --clear-cache. The user's cache
# folder is looked up for real, with XDG_CACHE_HOME pointing into the test's folder.
# Usage: cache_files_cli_test.sh CANOPY_LAYERS CANOPY_DEMO CANOPY_SCENE OUT [SHARED_ASSETS]
set -u
layers=$1 demo=$2 scene=$3 out=$4 assets=${5:-}
rm -rf "$out" && mkdir -p "$out"
out=$(cd "$out" && pwd)
export XDG_CACHE_HOME="$out/xdg"
cachedir="$XDG_CACHE_HOME/canopy"
fail() { echo "FAIL: $*"; exit 1; }
skipped=()

mkdir -p "$out/model"
"$scene" --scene shrub --faces 3K --out "$out/model/plant.glb" >/dev/null || fail "canopy-scene"
model="$out/model/plant.glb"
victim="$out/victim.txt"
printf 'a file of the user that no cache may touch\n' >"$victim"
cp "$victim" "$out/victim.orig"

# The three programs; each writes what it prints to $out/log, returns its exit code, and is
# stopped after $limit seconds (exit 124).
limit=120
prog_layers() { timeout $limit "$layers" "$model" --size 96x72 --out "$out/o_layers" "$@"; }
prog_demo() { timeout $limit "$demo" --gltf "$model" --frames 1 --size 96x72 --warmup 0 --no-mp4 --out "$out/o_demo" "$@"; }
prog_imp() { prog_demo --impostors far "$@"; }
programs=(prog_layers prog_demo prog_imp)
run() {  # program args... -> exit code; output in $out/log
  "$@" >"$out/log" 2>&1
}
expect_ok() {  # what program args...
  local what=$1; shift
  run "$@"
  local rc=$?
  [ $rc -eq 0 ] || fail "$what: $* exited $rc: $(tail -5 "$out/log")"
}
victim_unchanged() { cmp -s "$victim" "$out/victim.orig" || fail "$1: the linked file was changed"; }
# The kinds a program writes: canopy-layers and the demo the leaf roots, with impostors the views too.
kinds_of() { case $1 in prog_imp) echo "leafroots impostors" ;; *) echo "leafroots" ;; esac; }

# ---- 1. The default location is the user's cache folder, private, keyed by the model's path ----
before=$(ls -A "$out/model")
expect_ok "default location" prog_imp
[ -d "$cachedir" ] || fail "no cache folder $cachedir"
[ "$(stat -c %a "$cachedir")" = 700 ] || fail "cache folder mode $(stat -c %a "$cachedir"), expected 700"
lr=$(ls "$cachedir"/plant.glb-*.leafroots 2>/dev/null)
im=$(ls "$cachedir"/plant.glb-*.impostors 2>/dev/null)
[ -f "$lr" ] && [ -f "$im" ] || fail "caches not in $cachedir: $(ls -A "$cachedir")"
[ "$(ls -A "$out/model")" = "$before" ] || fail "something was written beside the model: $(ls -A "$out/model")"
expect_ok "second run" prog_imp
grep -q "^cache: leaf roots: read $lr" "$out/log" || fail "leaf roots not read: $(grep cache: "$out/log")"
grep -q "^cache: impostor views: read $im" "$out/log" || fail "views not read: $(grep cache: "$out/log")"
# Another model of the same file name elsewhere gets caches of its own.
mkdir -p "$out/other" && cp "$model" "$out/other/plant.glb"
run timeout $limit "$layers" "$out/other/plant.glb" --size 64x48 --out "$out/o_other" || fail "other model: $(tail -3 "$out/log")"
[ "$(ls "$cachedir"/plant.glb-*.leafroots | wc -l)" -eq 2 ] || fail "same-named models share a cache: $(ls "$cachedir")"
echo "default location: $cachedir (mode 700), nothing beside the model, read back"

# Final names of each kind in a location: the cache folder's or beside the model.
final_name() {  # location kind
  if [ "$1" = cache ]; then
    [ "$2" = leafroots ] && echo "$lr" || echo "$im"
  else
    echo "$model.$2"
  fi
}
beside_opt() { [ "$1" = beside ] && echo "--cache-beside-model"; }

# ---- 2. Links at every final and temporary name: the linked file is unchanged ----
# Each program's time here (no cache it may read: every one is rebuilt) is section 3's yardstick.
declare -A base_ms
for where in cache beside; do
  for p in "${programs[@]}"; do
    for k in leafroots impostors; do
      f=$(final_name $where $k)
      rm -rf "$f" "$f.tmp"
      ln -s "$victim" "$f"
      ln -s "$victim" "$f.tmp"
    done
    start=$(date +%s%N)
    expect_ok "links ($where)" $p $(beside_opt $where)
    base_ms[$where.$p]=$((($(date +%s%N) - start) / 1000000))
    victim_unchanged "$p, links $where"
    for k in $(kinds_of $p); do
      f=$(final_name $where $k)
      [ -f "$f" ] && [ ! -L "$f" ] || fail "$p ($where): $f is not a regular file after the write"
      grep -q "$f: a symbolic link" "$out/log" || fail "$p ($where): no line saying the link at $f was not used: $(grep -i "cache\|Leaves" "$out/log")"
    done
  done
done
rm -f "$model".*.tmp "$lr.tmp" "$im.tmp"
echo "links at final and temporary names, in the cache folder and beside the model: the linked file unchanged"

# ---- 3. A FIFO at every cache name: each program finishes, not blocked on the FIFO ----
# A program that opens the FIFO blocks for ever, so any finite limit catches it; the limit is the
# program's own time with no cache to read (section 2's run: a FIFO is never read either), times 3,
# at least 10 s, so that a loaded machine (ctest -j on two cores, sanitizers) does not fail it.
for where in cache beside; do
  for p in "${programs[@]}"; do
    base=${base_ms[$where.$p]}
    fifo_limit=$(( (3 * base + 999) / 1000 ))
    [ $fifo_limit -ge 10 ] || fifo_limit=10
    for k in leafroots impostors; do
      f=$(final_name $where $k)
      rm -rf "$f" && mkfifo "$f"
    done
    start=$(date +%s%N)
    limit=$fifo_limit run $p $(beside_opt $where)
    rc=$?
    took_ms=$((($(date +%s%N) - start) / 1000000))
    [ $rc -eq 0 ] || fail "$p with FIFOs ($where): exit $rc (124: still running after $fifo_limit s, 3x its $base ms without caches): $(tail -3 "$out/log")"
    grep -q "not a regular file (a FIFO)" "$out/log" || fail "$p ($where): no line naming the FIFO"
    echo "FIFOs ($where): $p finished in $took_ms ms (without caches $base ms, limit $fifo_limit s)"
  done
done

# ---- 4. A folder at every cache name: runs, says the cache was not written ----
for p in "${programs[@]}"; do
  for k in leafroots impostors; do
    f=$(final_name cache $k)
    rm -rf "$f" && mkdir "$f"
  done
  expect_ok "folders at the names" $p
  grep -q "not written: cannot write '$lr': Is a directory" "$out/log" || fail "$p: no line for the folder at $lr: $(grep -i "cache\|Leaves" "$out/log")"
done
rmdir "$lr" "$im"
echo "folders at the cache names: each program ran and said why nothing was written"

# ---- 5. Truncated, bit-flipped and oversized caches are rebuilt, saying why ----
expect_ok "fresh caches" prog_imp
for damage in truncate flip grow; do
  for f in "$lr" "$im"; do
    size=$(stat -c %s "$f")
    case $damage in
      truncate) truncate -s $((size - 7)) "$f"; why="truncated" ;;
      grow) printf 'x' >>"$f"; why="oversized" ;;
      flip) # the last byte of the contents, one bit
        b=$(od -An -tu1 -j $((size - 1)) -N1 "$f" | tr -d ' ')
        printf "$(printf '\\%03o' $((b ^ 16)))" | dd of="$f" bs=1 seek=$((size - 1)) conv=notrunc status=none
        why="damaged: the contents' checksum" ;;
    esac
  done
  expect_ok "$damage" prog_imp
  grep -q "^cache: leaf roots: $lr: $why.*; wrote it" "$out/log" || fail "$damage leaf roots: $(grep cache: "$out/log")"
  grep -q "^cache: impostor views: $im: $why.*; wrote it" "$out/log" || fail "$damage views: $(grep cache: "$out/log")"
  said=$(grep "^cache: impostor views" "$out/log" | sed "s|$cachedir/||")
  expect_ok "after $damage" prog_imp
  [ "$(grep -c "^cache: .*: read " "$out/log")" -eq 2 ] || fail "not read after rebuilding ($damage): $(grep cache: "$out/log")"
  echo "$damage: rebuilt, then read; the run said: $said"
done

# ---- 6. Two processes at once both finish with a valid cache ----
rm -f "$lr" "$im"
prog_imp --out "$out/o_demo1" >"$out/log1" 2>&1 &
a=$!
prog_imp --out "$out/o_demo2" >"$out/log2" 2>&1 &
b=$!
wait $a || fail "first of two at once: $(tail -3 "$out/log1")"
wait $b || fail "second of two at once: $(tail -3 "$out/log2")"
prog_layers --cache-dir "$out/shared" --out "$out/o_layers1" >"$out/log1" 2>&1 &
a=$!
prog_layers --cache-dir "$out/shared" --out "$out/o_layers2" >"$out/log2" 2>&1 &
b=$!
wait $a && wait $b || fail "canopy-layers twice at once"
expect_ok "after two at once" prog_imp
[ "$(grep -c "^cache: .*: read " "$out/log")" -eq 2 ] || fail "no valid cache after two at once: $(grep cache: "$out/log")"
expect_ok "after two at once" prog_layers --cache-dir "$out/shared"
grep -q "(read $out/shared/plant.glb-" "$out/log" || fail "canopy-layers: no valid cache after two at once"
[ -z "$(ls -A "$cachedir" "$out/shared" | grep '\.tmp')" ] || fail "temporary files left: $(ls -A "$cachedir" "$out/shared")"
echo "two processes at once (demo with impostors, canopy-layers): both exit 0, the caches read afterwards"

# ---- 7. A read-only model folder: nothing is written there ----
before=$(ls -A "$out/model")
for p in "${programs[@]}"; do
  expect_ok "read-only folder, default location" $p
done
[ "$(ls -A "$out/model")" = "$before" ] || fail "written beside the model: $(ls -A "$out/model")"
rm -f "$model".leafroots "$model".impostors
before=$(ls -A "$out/model")
# Root ignores permission bits: a read-only bind mount in a private mount namespace makes the folder
# read-only for real, and the opt-in beside-the-model location must then say it could not write.
if unshare -m --propagation private true 2>/dev/null; then
  export -f run prog_layers prog_demo prog_imp
  export layers demo model out limit
  for p in "${programs[@]}"; do
    unshare -m --propagation private bash -c "mount --bind '$out/model' '$out/model' && mount -o remount,bind,ro '$out/model' && $p --cache-beside-model" >"$out/log" 2>&1 ||
      fail "$p in a read-only folder: exit $?: $(tail -3 "$out/log")"
    grep -q "not written: cannot write '$model.leafroots': .*Read-only file system" "$out/log" || fail "$p: no line for the read-only folder: $(grep -i "cache\|Leaves" "$out/log")"
  done
  [ "$(ls -A "$out/model")" = "$before" ] || fail "written into the read-only folder: $(ls -A "$out/model")"
  echo "read-only model folder (read-only bind mount): nothing written there, each program said why"
else
  skipped+=("read-only bind mount (unshare -m not permitted here); the default-location check above ran")
fi

# ---- 8. A full disk: a clear line, no partial file, the run goes on ----
if unshare -m --propagation private true 2>/dev/null; then
  mkdir -p "$out/tiny"
  for p in prog_layers prog_imp; do
    unshare -m --propagation private bash -c "mount -t tmpfs -o size=8k tmpfs '$out/tiny' && $p --cache-dir '$out/tiny' && ls -A '$out/tiny' >'$out/tiny_listing'" >"$out/log" 2>&1 ||
      fail "$p on a full disk: exit $?: $(tail -3 "$out/log")"
    grep -q "not written: cannot write '$out/tiny/plant.glb-[0-9a-f]*.leafroots': No space left on device after [0-9]* of [0-9]* bytes (nothing was left behind)" "$out/log" ||
      fail "$p: no line for the full disk: $(grep -i "cache\|Leaves" "$out/log")"
    [ ! -s "$out/tiny_listing" ] || fail "$p left files on the full disk: $(cat "$out/tiny_listing")"
  done
  echo "full disk (8 KiB tmpfs): each program said so and left nothing"
else
  skipped+=("full tmpfs (unshare -m not permitted here); the file-size limit below ran")
fi
(
  trap '' XFSZ
  ulimit -f 8
  prog_layers --cache-dir "$out/limited" --out "$out/o_limited" --size 32x24 >"$out/log" 2>&1
) || fail "file-size limit: exit $?: $(tail -3 "$out/log")"
grep -q "not written: cannot write .*File too large after" "$out/log" || fail "file-size limit: no line: $(grep Leaves "$out/log")"
[ -z "$(ls -A "$out/limited")" ] || fail "partial file left: $(ls -A "$out/limited")"
echo "injected write failure (ulimit -f 8): clear line, nothing left"

# ---- 9. --clear-cache removes Canopy's files (a planted link, never its target) ----
ln -sf "$victim" "$cachedir/planted.glb.leafroots"
touch "$cachedir/notes.txt"
run "$layers" --clear-cache || fail "--clear-cache: $(cat "$out/log")"
grep -q "^removed [0-9]* cache files (.* MiB) from $cachedir$" "$out/log" || fail "--clear-cache said: $(cat "$out/log")"
[ "$(ls -A "$cachedir")" = "notes.txt" ] || fail "left after --clear-cache: $(ls -A "$cachedir")"
victim_unchanged "--clear-cache"
run "$demo" --cache-dir "$out/shared" --clear-cache || fail "demo --clear-cache"
[ -z "$(ls -A "$out/shared")" ] || fail "left after the demo's --clear-cache: $(ls -A "$out/shared")"
echo "--clear-cache: only Canopy's names removed, the planted link's target unchanged; the demo's: $(cat "$out/log")"

# ---- 10. A real glTF with its .bin and textures, links beside it ----
if [ -d "$assets/DiffuseTransmissionPlant" ]; then
  cp -r "$assets/DiffuseTransmissionPlant" "$out/real"
  ln -s "$victim" "$out/real/DiffuseTransmissionPlant.gltf.leafroots"
  ln -s "$victim" "$out/real/DiffuseTransmissionPlant.gltf.leafroots.tmp"
  run timeout $limit "$layers" "$out/real/DiffuseTransmissionPlant.gltf" --size 96x72 --out "$out/o_real" --cache-beside-model ||
    fail "real model: $(tail -3 "$out/log")"
  victim_unchanged "real model"
  echo "real model (DiffuseTransmissionPlant.gltf), links beside it: the linked file unchanged"
else
  skipped+=("the real-model case: shared assets folder absent ($assets)")
fi

for s in "${skipped[@]}"; do echo "SKIPPED (not a pass): $s"; done
echo "cache files: all checks that ran passed"
