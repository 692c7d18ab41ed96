"""suvtwin vehicle models: MJCF, parameter files and the builder (vehicle, road) → MjModel."""
