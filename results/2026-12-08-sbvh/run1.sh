cd /work/wt/sbvh
M=/work/main/target/release/forecast; N=/tmp/sbm/forecast-new
for i in 1 2 3; do
results/2026-12-08-sbvh/m.sh ring-main-$i $M scenes/ring.toml 128x128 256
results/2026-12-08-sbvh/m.sh ring-b13-$i $N scenes/ring.toml 128x128 256 SBVH_BUDGET=1.3 SBVH_ALPHA=1e-5
done
for i in 1 2 3; do
results/2026-12-08-sbvh/m.sh pool-main-$i $M scenes/external/sms-pool/scene.xml 192x108 32
results/2026-12-08-sbvh/m.sh pool-b13-$i $N scenes/external/sms-pool/scene.xml 192x108 32 SBVH_BUDGET=1.3 SBVH_ALPHA=1e-5
done
