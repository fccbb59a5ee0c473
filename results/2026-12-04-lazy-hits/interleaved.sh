# usage: bench3.sh SCENE RES SECONDS RUNS BIN...  -> samples/s per bin per run, interleaved
scene=$1; res=$2; sec=$3; runs=$4; shift 4
for r in $(seq 1 $runs); do for b in "$@"; do
  bin/$b render $scene --method ${METHOD:-pt} --accel embree --resolution $res --time ${sec}s --threads 2 --quiet --seed $r --out /tmp/b3 >/dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/b3.json'));print('$b',$r,round(j['samples_per_s']))"
done; done
