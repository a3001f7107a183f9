"""Probe slave for the status shim (tests/fmi/test_status_shim.py).

Integer parameter ``mode`` selects what it reports through the status protocol of
``drive_rattle_build.shim`` (it never raises, except in mode 5):

0. nothing (normal run, y = 2 u)
1. Error from exit_initialization_mode
2. Error from do_step (do_step still returns True)
3. Warning from do_step, plus a pythonfmu ``self.log`` message (seen only with debug logging)
4. Warning from the getter of the String output ``label``
5. do_step raises, which pythonfmu turns into fmi2Fatal

Every reported message contains ``%s %d 100%`` to prove it is never used as a format string.
"""

import ctypes

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

PERCENT = "%s %d 100%"
WARNING, ERROR = Fmi2Status.warning, Fmi2Status.error


class ShimProbe(Fmi2Slave):
    author = "drive-rattle tests"
    description = "Probe slave for the status shim"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.mode = 0
        self.u = 0.0
        self.y = 0.0
        self._fmi_status = ctypes.c_int(0)
        self._fmi_message = ""
        self.register_variable(Integer("mode", causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(String("label", causality=Fmi2Causality.output,
                                      variability=Fmi2Variability.discrete,
                                      getter=self._label))
        # The status channel, registered last.
        self.register_variable(String("_fmi.status_address", causality=Fmi2Causality.local,
                                      variability=Fmi2Variability.discrete,
                                      getter=lambda: hex(ctypes.addressof(self._fmi_status))),
                               nested=False)
        self.register_variable(String("_fmi.message", causality=Fmi2Causality.local,
                                      variability=Fmi2Variability.discrete,
                                      getter=lambda: self._fmi_message), nested=False)

    def _report(self, status, message):
        self._fmi_message = message
        self._fmi_status.value = status

    def _label(self):
        if self.mode == 4:
            self._report(WARNING, f"label getter warning {PERCENT}")
        return "probe label"

    def exit_initialization_mode(self):
        if self.mode == 1:
            self._report(ERROR, f"exit refused {PERCENT}")

    def do_step(self, current_time, step_size):
        if self.mode == 5:
            raise RuntimeError("probe raises in do_step")
        self.y = 2.0 * self.u
        if self.mode == 2:
            self._report(ERROR, f"step refused at t={current_time} {PERCENT}")
        elif self.mode == 3:
            self.log(f"pythonfmu log {PERCENT}", Fmi2Status.warning)
            self._report(WARNING, f"step warning {PERCENT}")
        return True
