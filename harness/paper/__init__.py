"""The paper's reproduction, an example of the product on the paper's Lynxmotion arm.

It uses the packages' public pieces; the product never imports it, except the registry's
extras and studies, which name it lazily. What is inside:

- identification: Table IV and the published 75-feature library
- planning: the paper's planning variants (its formulation), baselines and solver timings
- sections: the extras the Lynxmotion's registry entry declares for the bench
- studies: the paper's identification and planning studies (`torquebench study paper_*`)
"""
