"""The fitting stage of a diagnosis: the augmented model, its Gauss-Newton fit, evidence, friction paths, pool."""
