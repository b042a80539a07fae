#!/bin/bash
# usage: deaths_runs.sh BIN OUTROOT  -> runs every schedule, prints one line a run
BIN=$1; ROOT=$2; mkdir -p $ROOT
run() { # N seed sched name
  out=$ROOT/n$1-s$2-$4
  rm -rf $out
  nice -n 15 $BIN up --scenario configs/formation-$1.toml --executor inprocess --seed $2 --chaos-at $3 --out $out --quiet > $out.log 2>&1
  python3 - $out $1 $2 $3 $4 <<'PY'
import json,sys
o,n,s,sch,name=sys.argv[1:]
j=json.load(open(o+'/summary.json'))
f=j['mission']['formation']
plans=[(p['tick'],p['robot'],p.get('epoch'),round(p['gap'],3)) for p in f.get('plans',[])]
print(f"{n} s{s} {name} {sch}: formed={f.get('formed')} in_place={f.get('robots_in_place')} K={f.get('iterations')} L={f.get('path_length'):.1f} overlaps={f.get('overlapping_pairs')} ticks={j.get('ticks')} wall={j.get('wall_seconds'):.1f} plans={plans}")
PY
}
for s in 1 2 3; do
  run 100 $s 100:37,100:52 two
  run 100 $s 100:0,105:1 coord
  run 100 $s 60:37,62:38,64:39 three
  run 100 $s 100:37,100:74,100:2,100:83,100:71 five
  run 100 $s 100:37,110:52 gather
  run 100 $s 100:37,104:52 gather4
done
[ -n "$WITH500" ] && run 500 1 150:37,150:200,152:411 five00
# MASS=1: the mass-kill schedules (results/deaths-schedules.md, added 2026-12-04).
ids() { seq -s, -f "$1:%g" "${@:2}"; }
if [ -n "$MASS" ]; then
  for s in 1 2 3; do
    run 100 $s "$(ids 100 40 47)" eight
    run 100 $s "$(ids 100 10 23)" fourteen
    run 100 $s "$(ids 100 0 10 90)" tenth
  done
  [ -n "$WITH500" ] && run 500 1 "$(ids 150 100 119)" twenty00
fi
