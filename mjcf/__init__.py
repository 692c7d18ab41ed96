"""suvtwin vehicle models: MJCF, parameter files and the builder (vehicle, road) → MjModel."""

if __name__ != "suvtwin.mjcf":  # imported by its bare folder name
    raise ImportError(f"import suvtwin.mjcf, not {__name__} (suvtwin's layers are suvtwin.<layer>)")
