"""Study `paper_identification` (entry point: .section.run): coupled and per-joint sparse
identification vs the base-parameter oracle and pysindy (paper Figs. 2-8, Table III; Table IV
runs in the bench's identification section, the Lynxmotion's paper extra: harness.paper.sections).

Data: the default robot, `generate('lynxmotion', 4000, noise, seed=0)`, last 25 % held
out; a fresh excitation (seed 5) checks that the model predicts a trajectory it was not
trained on. The noise is drawn here from the clean torque with harness.data.sensors's
`torque_noise` (std = level x each joint's torque std, mean 0.2 std) and
`np.random.default_rng(seed)`. Each level gets its own draw (NOISE_SEEDS): seed 1 at
5 % is exactly the default data (generate(..., seed=0) draws its noise with seed 1),
1 % and 10 % use seeds 11 and 13, so the four rows are four experiments, not one draw
rescaled. Robustness: ROBUST_SEEDS, twenty independent draws at 5 % (ten in quick
mode; the first is the default data), each fitted by every method and by the oracle on
the same draw.

Methods: *per-joint* (the paper: each joint alone on the library features), *coupled*
(one Lagrangian of shared atoms; symmetric links, the default), *coupled general* (the
same without the symmetric-link assumption: sine companions and products of inertia),
*oracle* (two-step WLS on Pinocchio's base-parameter regressor: 16 dense base
parameters, the issue's reference; the truth is sparse in the atoms, so a sparse fit can
beat it: it is not an upper bound), *true support* (two-step WLS on exactly the true
atoms: what a perfect selector reaches on the draw; coupled / true support = 1 means the
selection cost nothing). Peers: pysindy STLSQ (threshold) and SSR (stopping point on its
elimination path), each swept and chosen on our validation blocks inside the training
part (identification.regression.peers); every reported time includes its sweep. Denoise then
regress: the coupled fit on the GCV-denoised training torque beside the raw one at every
noisy level (docs/identification.md, 'identification.identify', summarizes the outcome). "True terms" are the
library features with a non-zero coefficient in the exact noise-free least-squares fit
of the library; "true atoms" likewise for the Lagrangian atoms.
"""
