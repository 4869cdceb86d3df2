"""flexsat: controllers package."""
