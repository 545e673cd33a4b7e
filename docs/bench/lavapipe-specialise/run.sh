#!/usr/bin/env bash
# interleaved: for each round, each binary, each cell: the integrate+collide median (µs) and the substep's
# binaries clothlab-{base,rods,coulomb,still,none} in the current directory (see README.md)
for r in 1 2 3; do
  for cell in "vulkan default" "gl default" "vulkan bare"; do
    set -- $cell
    for v in base rods coulomb still none; do
      extra=""; [ "$2" = bare ] && extra="--scene bare.toml"
      out=o-$v
      rm -rf $out
      ./clothlab-$v bench --backends $1 --sizes 256 --iters 96 --no-overhead --resolution 64x64 --out $out $extra >/dev/null 2>&1
      ic=$(awk -F, '$4=="integrate+collide" {print $7/1000}' $out/results.csv)
      sub=$(awk -F, '$4=="substep" {print $7/1000}' $out/results.csv)
      echo "round $r $1-$2 $v $ic $sub"
    done
  done
done
