# Counts the pixels in which the H200's renders (run2.sh) differ from the CPU's on the same streams
# beyond the checks' relative 1e-4 (tests/photon_merging.rs, pixels_differing), read with
# Mitsuba's Bitmap (the optional venv of benches/). CPU renders: `hexray render scenes/S.json
# --backend cpu --method M --radius R --seed 7 --width 64 --height 64 --spp 16` into /tmp/ss_cpu/.
# GPU renders: same_streams_h200.tgz (the second call's, the same commands as run2.sh's) unpacked
# into /tmp/ss_gpu/.
import numpy as np, mitsuba as mi, sys
mi.set_variant('scalar_rgb')
def load(p): return np.array(mi.Bitmap(p), dtype=np.float64)[..., :3]
for s in ['tncg15_room','glass_room']:
  for m in ['sppm','vcm','vcm-full']:
    row=[]
    for r,f in [('0.1118034','0.01'),('0.3354102','0.03')]:
      g=load(f'/tmp/ss_gpu/ss/{s}_{m}_{r}.exr'); c=load(f'/tmp/ss_cpu/{s}_{m}_{r}.exr')
      t=((g-c)**2/(c*c+0.01)).mean(axis=2)
      row.append(f'{f}: {int((t>1e-8).sum())} px (largest {t.max():.3e}, relMSE {t.mean():.3e})')
    print(s, m, ' | '.join(row))
