"""Attitude estimators (batched runs), one folder per family; the model in :mod:`.model`."""
