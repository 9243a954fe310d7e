"""Scenes (SPEC section 1): :class:`~.scene.Scene`, loaders for names, ``.npy``, image
folders and videos (:mod:`.loaders`) and the built-in synthetic scenes
(:mod:`.library`)."""
