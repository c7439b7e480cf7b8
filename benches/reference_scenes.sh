# Sourced by the bench scripts: the reference scenes' rows, `scene_row NAME` printing
# "scene-radius reference reference-noise": the scene's bounding-sphere radius
# (merging::scene_radius), its deep 256x256 reference, and that reference's own noise
# (mean var_r / (r^2 + 0.01), `hexray compare`'s relmse_reference_noise).
scene_row() {
    case $1 in
    tncg15_room) echo "11.18034 out/methods/refs/tncg15_room_256.exr 6.594e-5" ;;
    glass_room) echo "11.18034 out/methods/refs/glass_room_256.exr 8.69e-5" ;;
    cornell_box) echo "480.3702 tests/data/references/cornell_box_256.npy 2.15e-5" ;;
    *) echo "unknown scene $1" >&2; exit 2 ;;
    esac
}
