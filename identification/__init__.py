"""suvtwin identification: quarter-car parameters per road class by a genetic algorithm.

Never imports MuJoCo: it consumes plain arrays produced by the pipeline.
"""
