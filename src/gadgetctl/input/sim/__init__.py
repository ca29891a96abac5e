"""Built-in simulated devices driven by keyboard/mouse events (reference section 9)."""
