"""flexsat: spacecraft package."""
