#!/bin/bash
# Issue 32 re-measurement on held-out seeds (code: the merged issue30-library tree = main + library).
B=${MOSLAM_BIN:-build/apps/moslam/moslam}
V=data/vocab/moslam_orb.mvoc
D=/work/lr/data; R=/work/lr/runs; mkdir -p $D $R
res=/work/lr/res.txt
one() { # name data fmt tag vocab extra...
  local name=$1 data=$2 fmt=$3 tag=$4 voc=$5; shift 5
  local out=$R/${name}_$tag
  rm -rf $out
  /usr/bin/time -f "%e s" -o $out.time $B run --dataset $fmt $data --settings $data/settings.yaml \
     --deterministic --quiet --mask-source synth-gt --vocabulary $voc --out $out "$@" > $out.log 2>&1
  echo "$name $tag $(/usr/bin/python3 docs/wip/issue32/prof.py $out $data 2>&1 | tail -1) $(cat $out.time)" >> $res
}
synth() { [ -d $D/$1_$2 ] || $B synth --preset $1 --seed $2 --out $D/$1_$2 --quiet > /dev/null 2>&1 || $B synth --preset $1 --seed $2 --out $D/$1_$2 > /dev/null 2>&1; }
fmt_of() { [ -f $1/times.txt ] && echo kitti || echo tum; }
for ps in "kitti_cars 7" "street_repeat 4" "corridor 3" "kitti_cars 8"; do
  set -- $ps; synth $1 $2; d=$D/$1_$2; f=$(fmt_of $d)
  one $1_$2 $d $f on $V
  one $1_$2 $d $f off $V --no-loop-closing
done
# loop_room: vocabulary from seed 2's frames (as docs/EVALUATION.md); held-out seeds 11, 12
synth loop_room 2
[ -f /work/lr/voc_s2.mvoc ] || $B vocab train --images $D/loop_room_2/rgb --every 5 --k 10 --levels 3 --out /work/lr/voc_s2.mvoc > /work/lr/voc.log 2>&1
for s in 11 12; do
  synth loop_room $s; d=$D/loop_room_$s
  one loop_room_$s $d tum on /work/lr/voc_s2.mvoc
  one loop_room_$s $d tum noverif /work/lr/voc_s2.mvoc --no-loop-verification
  one loop_room_$s $d tum off /work/lr/voc_s2.mvoc --no-loop-closing
done
for ps in "street_repeat_loop 4" "corridor_loop 3"; do
  set -- $ps; synth $1 $2; d=$D/$1_$2; f=$(fmt_of $d)
  one $1_$2 $d $f on $V
  one $1_$2 $d $f off $V --no-loop-closing
done
echo finished >> $res
