"""The paper's reproduction, an example of the product on the paper's Lynxmotion arm.

It uses the packages' public pieces; the product never imports it: the registry's extras
and `identify --library paper` (harness.robots.extras) and the studies (harness.studies)
name it and import it on first use. What is inside:

- identification: Table IV (table4) and the published 75-feature library (published_library)
- planning: the paper's planning variants (its formulation) and baselines
- sections: the extras the Lynxmotion's registry entry declares for the bench
- studies: the paper's identification and planning studies (`torquebench study paper_*`)
"""
