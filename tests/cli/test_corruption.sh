#!/usr/bin/env bash
# Corruption is detected (issue 18 item 4; docs/output.md, "Corruption"):
# one byte of a real run file is flipped at each of 100 offsets spread
# over the whole file, and the copy is resumed.  Every outcome must be a
# correct resume (exit 0, the final positions those of resuming the intact
# file, bit for bit) or a clear refusal (exit 2 with a message); never a
# crash, another exit status, or a resume that carries a corrupted value
# on.  Checksums: Fletcher-32 on every chunked dataset (docs/output.md).
# usage: test_corruption.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
cfg="$src/configs/protocols/ci/radial_spheres.yaml"
"$capdem" run "$cfg" --output ref.h5 --steps 2000 --quiet 2> err || { bad "the reference run failed"; exit 1; }
cp ref.h5 good.h5
"$capdem" run "$cfg" --resume good.h5 --steps 2100 --quiet 2> err || { bad "resuming the intact file failed"; exit 1; }
size=$(stat -c %s ref.h5)
flip() { # FILE OFFSET: xor one byte with 0x5a
  local b
  b=$(od -An -tu1 -j "$2" -N1 "$1" | tr -d ' ')
  printf "$(printf '\\%03o' $(( b ^ 90 )))" | dd of="$1" bs=1 seek="$2" conv=notrunc status=none
}
same=0 refused=0
n_flips=100
for i in $(seq 0 $((n_flips - 1))); do
  off=$(( size * i / n_flips + 13 ))
  cp ref.h5 t.h5
  flip t.h5 "$off"
  timeout 120 "$capdem" run "$cfg" --resume t.h5 --steps 2100 --quiet > out 2> err
  rc=$?
  if [ $rc -eq 0 ]; then
    if h5diff good.h5 t.h5 /particles/all/position/value > /dev/null 2>&1; then
      same=$((same+1)); ok
    else
      bad "byte $off flipped: the resume went on with other positions"
    fi
  elif [ $rc -eq 2 ] && [ -s err ]; then
    refused=$((refused+1)); ok
  else
    bad "byte $off flipped: exit $rc"
  fi
done
echo "$same resumed correctly, $refused refused (exit 2), $fails otherwise, of $n_flips flipped bytes in a $size-byte file"
[ $fails -eq 0 ]
