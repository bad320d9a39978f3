#!/usr/bin/env bash
# Measures the GPU backend on a lent hardware GPU (issue 41; docs/PERFORMANCE.md "The GPU backend
# on hardware"). The GPU machine has none of our Debian libraries and no package registry, so:
#
#   here:  bash scripts/gpu-hardware.sh pack    # build/bin's programs and their libraries into
#                                               # .gpurun/bundle.tar.xz, the Vulkan loader's
#                                               # Debian packages into .gl/ (both untracked)
#   there: bash scripts/gpu-hardware.sh run     # OUT=folder for the logs (default out/gpu-hw)
#
# `run` unpacks the bundle and the Vulkan loader (.gl/*.deb, fetched as the device notes say),
# runs the GPU tests (GPU = CPU on hardware), the per-pass timings of RC and HRC (f32, f16) at
# 256^2 .. 4096^2, the CLI on the example scenes (2D rc and hrc, 3D ssrc) and a CPU-GPU compare.
# Every step has its own time limit, so one that hangs cannot take the others' time.
set -u
mode=${1:-}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
programs="penumbra penumbra_gpu_passes penumbra_tests penumbra_make_scenes penumbra_scene_family"

if [ "$mode" = pack ]; then
  rm -rf .gpurun/stage && mkdir -p .gpurun/stage/bin .gpurun/stage/lib
  for p in $programs; do cp build/bin/$p .gpurun/stage/bin/; done
  # Every library but glibc's own (the machine has a newer glibc; ours would not load under it).
  ldd $(for p in $programs; do echo build/bin/$p; done) | awk '$3 ~ /^\// {print $3}' | sort -u |
    grep -vE '/(libc|libm|libdl|libpthread|librt|ld-linux[^/]*)\.so' |
    while read -r lib; do cp -L "$lib" .gpurun/stage/lib/; done
  cp -L /lib/x86_64-linux-gnu/libvulkan.so.1 .gpurun/stage/lib/
  # The loader and GL dispatch libraries the NVIDIA driver's ICD loads, unpacked over / there.
  if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
    mkdir -p .gl && (cd .gl && apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 \
      libglx0 libgles2)
  fi
  tar -C .gpurun/stage -cf - bin lib | xz -T2 -6 >.gpurun/bundle.tar.xz
  rm -rf .gpurun/stage
  ls -la .gpurun/bundle.tar.xz
  exit 0
fi
[ "$mode" = run ] || { echo "usage: $0 pack|run" >&2; exit 2; }

out=${OUT:-out/gpu-hw}
mkdir -p "$out"
log() { echo "== $*"; }
if [ -z "${LOCAL:-}" ]; then  # LOCAL=1: a rehearsal on this machine's lavapipe
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
nv=/usr/local/nvidia/share
[ -f $nv/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=$nv/vulkan/icd.d/nvidia_icd.json
[ -f $nv/glvnd/egl_vendor.d/10_nvidia.json ] &&
  export __EGL_VENDOR_LIBRARY_FILENAMES=$nv/glvnd/egl_vendor.d/10_nvidia.json
mkdir -p /tmp/p && xz -dc .gpurun/bundle.tar.xz | tar -C /tmp/p -xf -
export LD_LIBRARY_PATH=/tmp/p/lib
# The tests hold the paths they were built with (/work/main/build/bin/...).
mkdir -p build/bin && cp /tmp/p/bin/* build/bin/
[ -e /work/main ] || { mkdir -p /work && ln -s "$root" /work/main; }
bin=/work/main/build/bin

log machine
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm,clocks.mem \
  --format=csv | tee "$out/machine.txt"
nproc | tee -a "$out/machine.txt"
# The card's copy bandwidth (bytes read + written), the ceiling for HRC's merges.
timeout 60 env -u LD_LIBRARY_PATH python3 - <<'EOF' 2>&1 | tee -a "$out/machine.txt"
import torch
a = torch.empty(2 * 1024**3, dtype=torch.uint8, device="cuda").random_(0, 255)
b = torch.empty_like(a)
for _ in range(3): b.copy_(a)
s, e = torch.cuda.Event(enable_timing=True), torch.cuda.Event(enable_timing=True)
ts = []
for _ in range(10):
    s.record(); b.copy_(a); e.record(); torch.cuda.synchronize(); ts.append(s.elapsed_time(e))
ts.sort()
print(f"device copy: {2 * a.numel() / ts[5] / 1e6:.0f} GB/s (read + write, median of 10)")
EOF

log tests
timeout 240 $bin/penumbra_tests \
  --gtest_filter="${FILTER:-Gpu.*:SsrcGpu.*:Cli.GpuRender*:Cli3d.SsrcRendersOnTheGpu*}" 2>&1 |
  tee "$out/tests.log" | grep -E '^\[  (FAILED|PASSED) |OK \]|Vulkan|device' | head -60

# Each case again in a process of its own: a case that fails only after many others is a
# resource the driver ran out of, not the case.
ulimit -n
for t in $(grep -E '^\[  FAILED  \] [A-Za-z]+\.[A-Za-z]+ \(' "$out/tests.log" | awk '{print $4}'); do
  timeout 60 $bin/penumbra_tests --gtest_filter="$t" 2>&1 | tail -3
done

log passes
sizes=${SIZES:-256,512,1024,2048,4096} runs=${RUNS:-9}
{
  timeout 120 $bin/penumbra_gpu_passes --method hrc --sizes $sizes --runs $runs
  timeout 120 $bin/penumbra_gpu_passes --method hrc --storage f16 --sizes $sizes --runs $runs
  timeout 150 $bin/penumbra_gpu_passes --method rc --sizes $sizes --runs $(((runs + 2) / 3))
} 2>&1 | tee "$out/passes.txt"

log cli
{
  for s in ${SCENES:-scenes/*.json}; do
    for m in rc hrc; do
      echo "## $s $m"
      timeout 60 $bin/penumbra render "$s" --method $m --device gpu --json -o /tmp/r.pfm
    done
  done
  for s in scenes/3d/cornell.json scenes/3d/four_cubes.json scenes/3d/bunny_sky.json; do
    echo "## $s ssrc ${SSRC_SIZE:-1920x1080}"
    w=${SSRC_SIZE:-1920x1080}
    timeout 60 $bin/penumbra render "$s" --method ssrc --device gpu --width ${w%x*} --height ${w#*x} \
      --json -o /tmp/r.pfm
  done
} >"$out/cli.jsonl" 2>&1
grep -cE '"device"' "$out/cli.jsonl"

log compare
# GPU against CPU on the same scene and options: relative RMSE and the largest difference.
metric() { env -u LD_LIBRARY_PATH python3 -c 'import json,sys; d=json.load(sys.stdin); print("relative RMSE", d["relative_rmse"], "max |diff|", d["max_abs"])'; }
for m in rc hrc; do
  timeout 60 $bin/penumbra render scenes/cornell.json --method $m --device gpu -o /tmp/g.pfm --json
  timeout 120 $bin/penumbra render scenes/cornell.json --method $m --device cpu -o /tmp/c.pfm --json
  echo "## $m cornell gpu vs cpu: $($bin/penumbra compare /tmp/g.pfm /tmp/c.pfm --scene scenes/cornell.json --json | metric)"
done >"$out/compare.txt" 2>&1
for s in cornell four_cubes; do
  w=${SSRC_SIZE:-1920x1080}
  timeout 60 $bin/penumbra render scenes/3d/$s.json --method ssrc --device gpu --width ${w%x*} \
    --height ${w#*x} -o /tmp/g.pfm --json
  timeout 120 $bin/penumbra render scenes/3d/$s.json --method ssrc --device cpu --width ${w%x*} \
    --height ${w#*x} -o /tmp/c.pfm --json
  echo "## ssrc $s $w gpu vs cpu: $($bin/penumbra compare /tmp/g.pfm /tmp/c.pfm --radiance --json | metric)"
done >>"$out/compare.txt" 2>&1
grep '^## ' "$out/compare.txt"
log summary
grep -E 'total|wall|merge|trace' "$out/passes.txt" | grep -v 'first render' | cut -c1-110
log done
