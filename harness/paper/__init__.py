"""The paper's reproduction: an example of the product, built from its public pieces."""
