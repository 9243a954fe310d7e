"""Receptive fields (SPEC section 2): the DoG / Gauss kernels and model ladders
(:mod:`.receptive_fields`), their geometry (:mod:`.orbits`: radius, 8-fold symmetry,
orbits) and zero-padded filtering with its adjoint (:mod:`.filtering`)."""
