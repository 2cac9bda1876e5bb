#!/usr/bin/env bash
# A run file written by REF resumes with NEW to the same bits as with REF
# (and the reverse: a file written by NEW resumes with REF to the same bits).
# usage: resume_check.sh REF NEW OUT CONFIG STEPS_FIRST STEPS_END BACKEND
set -u
ref=$1 new=$2 out=$3 cfg=$4 s1=$5 s2=$6 be=$7
name=$(basename "$cfg" .yaml)-$be
mkdir -p "$out"
export OMP_NUM_THREADS=1
for w in ref new; do
  bin=$ref; [ $w = new ] && bin=$new
  [ -s "$out/$name-first-$w.h5" ] || "$bin" run "$cfg" --backend $be --steps $s1 --output "$out/$name-first-$w.h5" --overwrite --quiet || { echo "FAIL first $w"; exit 1; }
done
for w in ref new; do for r in ref new; do
  bin=$ref; [ $r = new ] && bin=$new
  cp "$out/$name-first-$w.h5" "$out/$name-$w-by-$r.h5"
  "$bin" run "$cfg" --backend $be --resume "$out/$name-$w-by-$r.h5" ${s2:+--steps $s2} --quiet || { echo "FAIL resume $w by $r"; exit 1; }
done; done
rc=0
for pair in "ref-by-ref ref-by-new" "ref-by-ref new-by-ref" "ref-by-ref new-by-new"; do
  set -- $pair
  if h5diff --exclude-attribute /h5md/creator "$out/$name-$1.h5" "$out/$name-$2.h5" > "$out/$name-$1-vs-$2.diff" 2>&1; then
    echo "ok   $name: written by ${1%%-*}, resumed by ${1##*-} == written by ${2%%-*}, resumed by ${2##*-}"
  else echo "DIFF $name: $1 vs $2 ($(grep -c 'differences found' "$out/$name-$1-vs-$2.diff") datasets)"; rc=1; fi
done
exit $rc
