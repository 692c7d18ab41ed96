"""suvtwin estimators: UKF, IMM and the tire-pressure estimators of the seed papers.

Never imports MuJoCo: estimators take plain arrays.
"""
