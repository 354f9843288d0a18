"""Mixed-precision gradient updates (``update_dtype: bfloat16``) for CPUs with bfloat16 units.

The learner's minibatch passes run their matrix products in bfloat16 under `torch.autocast`
(weights, optimiser state, losses and the saved agent stay float32); collection — the policy
acting in the env — is untouched, so the rollout's log-probabilities and values are float32.
On a CPU with AMX or AVX-512 BF16 units oneDNN runs those products at about twice the float32
rate for 256-wide layers and 1.2–1.5× for 64-wide ones (`auv-gym speed training
--update-dtype bfloat16`, docs/performance.md); on CPUs without them bfloat16 is emulated and
slower. The learned agent differs from a float32 run (bfloat16 keeps 8 significant bits), so a
configuration states the choice and `metadata.json` records it.
"""

from __future__ import annotations

import functools
from typing import Any

__all__ = ["UPDATE_DTYPES", "check_update_dtype", "use_update_dtype"]

UPDATE_DTYPES = ("float32", "bfloat16")


def check_update_dtype(value: Any, where: str) -> str:
    """``value`` if it names an update precision; ValueError naming ``where`` otherwise."""
    if not isinstance(value, str) or value not in UPDATE_DTYPES:
        raise ValueError(f"{where}: update_dtype must be one of {list(UPDATE_DTYPES)}, got "
                         f"{value!r}")  # fmt: skip
    return value


def use_update_dtype(model: Any, dtype: str) -> None:
    """Run ``model.train`` (the SB3 update; its collection is left alone) with matrix products
    in ``dtype``; "float32" leaves the model as it is."""
    check_update_dtype(dtype, "use_update_dtype")
    if dtype == "float32":
        return
    import torch

    algorithm = type(model)
    update = algorithm.train

    @functools.wraps(update)
    def mixed_precision_update(self: Any, *args: Any, **kwargs: Any) -> Any:
        with torch.autocast("cpu", dtype=torch.bfloat16):
            return update(self, *args, **kwargs)

    # A subclass, not an instance attribute: SB3 saves the instance's __dict__ (a closure there
    # would be pickled with the model), never its class; a loaded model is plain again, and the
    # trainer applies the precision to it afresh.
    model.__class__ = type(
        algorithm.__name__, (algorithm,), {"train": mixed_precision_update, "__module__": __name__}
    )
