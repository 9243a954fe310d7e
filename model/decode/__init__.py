"""From spikes back to images and scores (SPEC section 4): reconstruction
(:mod:`.reconstruction`), the least-squares inverse (:mod:`.inverse`), metrics
(:mod:`.metrics`), evaluation against a scene (:mod:`.evaluation`) and its streaming form
(:mod:`.streaming`)."""
