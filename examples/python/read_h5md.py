# Reading an H5MD trajectory of `sesi run` with h5py (docs/scene-format.md, "Trajectory in H5MD"),
# after `sesi run examples/scenes/sphere-pole-crossing.toml --trajectory-format h5md`.
import h5py
with h5py.File("sesi-out/sphere-pole-crossing/trajectory.h5", "r") as f:
    t = f["particles/all/position/time"][:]       # [frames]
    x = f["particles/all/position/value"][:]      # [frames, bodies, D]
    print(len(t), x.shape, t[-1], x[-1, 0])       # last embedding point of body 1
