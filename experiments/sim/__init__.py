"""The simulations, as a library layer: closed loops called with typed configuration.

Imports only :mod:`estim`, :mod:`guidance` and the noise models
(:mod:`experiments.noise`); raises ``ValueError`` (pydantic's ``ValidationError`` is
one) and never reads files or command-line dicts. Above it: scenario files
(:mod:`kalman_vs_infoset.experiments.scenario`), the runner, the commands, provenance and plots.

* :mod:`.intercept` -- one engagement (setup / step / finish) of an
  :class:`.intercept_config.InterceptScenario`;
* :mod:`.pointing` -- the attitude loop holding the interceptor's axis (end-to-end);
* :mod:`.attitude_rw`, :mod:`.attitude_cmg`, :mod:`.gyrostat` -- the attitude loops of
  seeds 001/002, 000 and 004, configured by the typed scenarios of
  :mod:`.attitude_rw_config`, :mod:`.attitude_cmg_config` (through
  :class:`.turn_setup.TurnSetup`) and :mod:`.gyrostat_config`;
* :mod:`.estimator_loop` -- a registered attitude estimator run over a batch of runs;
* :mod:`.fields` -- the typed tables' building blocks and their one-line errors.
"""
