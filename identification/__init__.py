"""suvtwin identification: quarter-car parameters per road class by a genetic algorithm.

Never imports MuJoCo: it consumes plain arrays produced by the pipeline.
"""

if __name__ != "suvtwin.identification":  # imported by its bare folder name
    raise ImportError(f"import suvtwin.identification, not {__name__} (suvtwin's layers are suvtwin.<layer>)")
