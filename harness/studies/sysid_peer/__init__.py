"""Study `sysid_peer`: MuJoCo's own system-identification toolbox (mujoco.sysid) beside the
project's `identify` on the real Panda log: peer (its fit), scoring (the figures judged),
section (the study's run)."""
