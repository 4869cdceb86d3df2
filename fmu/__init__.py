"""flexsat: fmu package."""
