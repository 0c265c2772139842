"""Looking up a variable name the user typed: a refusal that suggests the close matches. The one
implementation is gimbal2axis.errors.did_you_mean, which the scene checks use as well (errors sits
below every layer)."""
from __future__ import annotations

from ..errors import did_you_mean

__all__ = ["did_you_mean"]
