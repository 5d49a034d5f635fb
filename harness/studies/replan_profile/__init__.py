"""Study `replan_profile`: an anytime-SQP iteration and a warm re-plan cut into their parts
(harness.studies.replan_profile.section)."""
