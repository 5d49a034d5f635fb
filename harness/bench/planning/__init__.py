"""Bench section "planning" (entry point: .section.run): energy-optimal planning around a
moving obstacle with the robot's closed-form model and with the identification section's
model, and the planner's speed on that robot.

The motion is the robot's registered one (harness.plan.arm_config.bench_motion), from rest to
rest. Its unobstructed energy optimum (closed form) is planned first; an obstacle then
crosses the middle of one moving link of that optimum at mid-time, sweeping 0.5 m upward
(planning.scenarios.crossing_scenario), and the arm plans and re-plans around it
(Algorithm 2) with each model. A robot's declared extras (harness.robots.extras) add
their scenarios. The plans go on to the replay section.
"""
