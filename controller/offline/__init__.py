"""The offline effort: can this body perform this motion without any external force?
A sampling search over the servo targets (:mod:`controller.offline.samcon`, after SAMCON)
scored by a state cost against the reference (:mod:`controller.offline.cost`), its result
replayed (:mod:`controller.offline.record`). Tuned by the configuration's ``offline``
section (:class:`controller.config.OfflineConfig`)."""

from controller.offline.record import OfflineResult, perform

__all__ = ["OfflineResult", "perform"]
