"""Many solves of one model: a scene or a problem prepared once
(:mod:`~contactqp.many.prepared`: :func:`prepare`, :class:`Prepared`), and a batch of its
cases solved and checked together (:mod:`~contactqp.many.batch`: :class:`Batch`)."""

from contactqp.many.batch import Batch
from contactqp.many.prepared import Prepared, prepare

__all__ = ["Batch", "Prepared", "prepare"]
