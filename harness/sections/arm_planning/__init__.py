"""Bench section (entry point: .section.run) for any arm but the Lynxmotion: energy-optimal
planning around a moving obstacle with the arm's closed-form model and with a model
identified from 5 % noise data, and the planner's speed on that arm.

The motion is the robot's registered one (harness.robots.arm.bench_motion). Its
unobstructed energy optimum (closed form) is planned first; an obstacle then crosses the
middle of one moving link of that optimum at mid-time, sweeping 0.5 m upward
(planning.scenarios.crossing_scenario), and the arm plans and re-plans around it
(Algorithm 2) with each model. The plans go on to the arm_replay section.
"""
