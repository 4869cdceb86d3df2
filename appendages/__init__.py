"""flexsat: appendages package."""
