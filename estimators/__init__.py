"""suvtwin estimators: UKF, IMM and the tire-pressure estimators of the seed papers.

Never imports MuJoCo: estimators take plain arrays.
"""

if __name__ != "suvtwin.estimators":  # imported by its bare folder name
    raise ImportError(f"import suvtwin.estimators, not {__name__} (suvtwin's layers are suvtwin.<layer>)")
