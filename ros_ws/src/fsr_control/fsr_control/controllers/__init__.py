"""Control laws returning a body wrench: geometric (fixed rotors) and Voliro (tilting rotors)."""
