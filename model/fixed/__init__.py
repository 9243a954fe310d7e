"""The bit-accurate fixed-point twin (SPEC section 5): the contract the RTL implements."""
