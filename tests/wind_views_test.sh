#!/bin/sh
# Issue 66's bounds, kept (ctest WindViews): the 2D method's field keeps >= 0.9 of its foliage
# pixels on every frame of a 360-degree orbit and from yaw 90 in the default wind, and the shrub's
# crown sways mirrored between yaw 0 and yaw 180 (correlation <= -0.6). scripts/wind_views.py
# --quick --check: fewer frames than the figures of record (docs/performance.md "The wind from
# every side"), the same measure (canopy-demo --measure-foliage).
#   wind_views_test.sh DEMO SOURCE_DIR OUT_DIR
demo=$1 src=$2 out=$3
rm -rf "$out" && mkdir -p "$out" || exit 1
python3 "$src/scripts/wind_views.py" "$demo" "$out/field" --scenes field --methods 2d --cases orbit,yaw90 --quick --check || exit 1
python3 "$src/scripts/wind_views.py" "$demo" "$out/shrub" --scenes shrub --methods 2d --cases mirror --quick --check || exit 1
