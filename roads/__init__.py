"""suvtwin roads: ISO 8608 road profiles, their specifications and roughness classification.

The bottom layer with :mod:`suvtwin.errors` and :mod:`suvtwin.files`: imports no other layer and
never MuJoCo.
"""

if __name__ != "suvtwin.roads":  # imported by its bare folder name
    raise ImportError(f"import suvtwin.roads, not {__name__} (suvtwin's layers are suvtwin.<layer>)")
