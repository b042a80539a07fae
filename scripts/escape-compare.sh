#!/bin/bash
# The escape (agent/src/behaviours/formation/escape.rs) on and off, side by side, one binary:
# usage: escape-compare.sh BIN OUTROOT. Every run twice, once as shipped and once with
# `formation.kernels.escape.after_ticks = 0` appended to a copy of its scenario; one line a run.
# With BIN_OFF=<other binary> set, the "off" runs are that binary's on the unchanged scenario
# (two builds side by side). RANDOM_KILLS=1 (or 2) adds the 20 random schedules of
# results/deaths-schedules.md ("Random schedules") under swaps and relayed at 100 robots.
BIN=$1; ROOT=$2; mkdir -p $ROOT
list=$ROOT/runs.txt; : > $list
add() { echo "$*" >> $list; } # name scenario seed schedule max_ticks
sed 's/^pattern = "optimise"/pattern = "fixed"/' configs/formation-100-centralised.toml > $ROOT/fixedC.toml
grid="none 100:37 100:0 30:0 100:37,100:52 100:0,105:1 100:37,100:74,100:2,100:83,100:71 20:37,20:0 60:37,62:38,64:39 100:37,110:52 50:5,50:6,50:7"
for s in 1 2 3; do
  for k in $grid; do
    add fixedC $ROOT/fixedC.toml $s $k 3000
    add optC configs/formation-100-centralised.toml $s $k 3000
  done
  for k in 100:37,100:52 100:0,105:1 60:37,62:38,64:39 100:37,100:74,100:2,100:83,100:71 100:37,110:52 100:37,104:52 \
      $(seq -s, -f "100:%g" 40 47) $(seq -s, -f "100:%g" 10 23) $(seq -s, -f "100:%g" 0 10 90); do
    add swaps100 configs/formation-100.toml $s $k 3000
  done
  for sc in formation formation-n formation-r; do
    for k in none 0:0 15:0 5:0,10:1,15:2 10:1,10:2,10:3,10:4,10:5,10:6,10:7; do
      add $sc configs/$sc.toml $s $k 1000
    done
  done
  add swaps16 configs/formation-swaps-16.toml $s 30:3,30:4 1000
done
if [ -n "$RANDOM_KILLS" ]; then
  while read -r name seed k; do
    add random-swaps-$name configs/formation-100.toml $seed $k 3000
    add random-relay-$name configs/formation-100-centralised.toml $seed $k 3000
  done <<'LIST'
r0 17 135:1,133:45,146:10,147:26
r1 27 60:70,50:82
r2 36 36:75,42:47,24:23,38:88
r3 35 116:25,115:0,112:72
r4 20 56:10
r5 4 70:49,60:25,57:77
r6 35 37:6,42:57,30:30,41:29
r7 26 12:95
r8 19 140:42
r9 7 47:4,56:87,55:75,40:12
r10 36 104:94,101:74
r11 17 18:35
r12 21 81:71,87:73
r13 30 48:23
r14 23 145:49
r15 10 140:83,123:96
r16 32 123:48,118:92,123:45
r17 4 132:92,123:44,126:9,132:63
r18 14 30:18,28:83
r19 39 16:66,25:97
LIST
fi
# RANDOM_KILLS=2 adds the 24 heavier schedules drawn 2026-12-06 (1-12 kills, in transit too).
if [ "$RANDOM_KILLS" = 2 ]; then
  while read -r name seed k; do
    add random-swaps-$name configs/formation-100.toml $seed $k 3000
    add random-relay-$name configs/formation-100-centralised.toml $seed $k 3000
  done <<'LIST'
t0 79 85:40,86:41
t1 88 20:39,14:7,22:59,19:63
t2 66 59:21,65:22,61:23,69:24
t3 84 145:2,148:93,141:81,145:29,154:23,141:75,141:34,142:65
t4 68 86:56,81:48
t5 42 153:96,165:35,160:25
t6 70 97:7,99:18
t7 79 11:80,20:97,14:29
t8 65 144:23,142:63,143:30,143:47,137:69,134:24,133:1,131:27
t9 77 103:0,114:1,102:2,116:3
t10 78 116:89,117:40,105:47,106:42,115:38,103:71,117:68,115:64,108:96,105:97,104:45,104:61
t11 64 42:17,39:21
t12 79 92:7,91:8,98:9,103:10
t13 53 129:37,136:38,122:39,122:40,127:41,137:42,123:43,127:44,133:45,130:46,131:47,126:48
t14 88 84:87,85:88
t15 48 94:15,94:16
t16 60 145:9,144:10,145:11,147:12
t17 43 92:94,90:95
t18 46 153:78,153:66,146:28,152:36,156:45,157:83
t19 83 19:93,19:94,21:95,25:96
t20 45 92:52,83:67,80:64
t21 49 110:32,114:33
t22 59 154:32,161:67,155:14,150:45
t23 81 142:18,140:19,137:20,140:21
LIST
fi
one() { # name scenario seed schedule max_ticks mode
  name=$1; sc=$2; s=$3; k=$4; mt=$5; mode=$6
  out=$ROOT/$name-s$s-$(echo $k | md5sum | cut -c1-8)-$mode
  bin=$BIN
  if [ $mode = off ] && [ -n "$BIN_OFF" ]; then bin=$BIN_OFF
  elif [ $mode = off ]; then cp $sc $out.toml; printf '\n[formation.kernels.escape]\nafter_ticks = 0\n' >> $out.toml; sc=$out.toml; fi
  chaos=(); [ $k != none ] && chaos=(--chaos-at $k)
  nice -n 10 $bin up --scenario $sc --executor inprocess --seed $s "${chaos[@]}" --max-ticks $mt --out $out --quiet > $out.log 2>&1
  python3 - $out $name $s $k $mode <<'PY'
import json,sys
o,n,s,k,m=sys.argv[1:]
try:
    j=json.load(open(o+'/summary.json')); f=j['mission']['formation']
    print(f"{n} s{s} {k} {m}: formed={f.get('formed')} in_place={f.get('robots_in_place')} K={f.get('iterations')} L={f.get('path_length'):.3f} overlaps={f.get('overlapping_pairs')}")
except Exception as e:
    print(f"{n} s{s} {k} {m}: ERROR {e}")
PY
}
export -f one; export BIN ROOT BIN_OFF
while read -r line; do for m in on off; do echo "$line $m"; done; done < $list | xargs -P 2 -L 1 bash -c 'one "$@"' _ > $ROOT/results.txt
sort $ROOT/results.txt > $ROOT/sorted.txt
python3 - $ROOT/sorted.txt <<'PY'
import sys,collections
rows=collections.defaultdict(dict)
for l in open(sys.argv[1]):
    key,rest=l.split(': ',1); *k,m=key.split(' '); rows[' '.join(k)][m]=rest.strip()
same=diff=0
for k,v in sorted(rows.items()):
    if v.get('on')==v.get('off'): same+=1
    else:
        diff+=1; print(f"DIFF {k}\n  on:  {v.get('on')}\n  off: {v.get('off')}")
print(f"{same} runs identical, {diff} differ")
PY
