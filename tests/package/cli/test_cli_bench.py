"""`gimbal2axis bench` says a cost per step that is a difference of two measured times only when it
stands out of the repeats' noise: never a negative cost (issue: "master's own -0.04 us per step")."""
import pytest

from gimbal2axis.cli.bench import cost_text

pytestmark = pytest.mark.python_bound


@pytest.mark.parametrize("cost, noise", [(-0.04, 0.0), (-0.04, 0.3), (0.2, 0.3), (0.0, 0.0)])
def test_a_cost_within_the_noise_is_said_to_be_so(cost, noise):
    text = cost_text(cost, noise)
    assert text.startswith("below the noise"), text
    assert f"{cost:+.2f} us per step measured" in text   # the measurement is kept, as what it is


def test_a_cost_above_the_noise_is_a_number_with_its_noise():
    assert cost_text(9.07, 0.5) == "9.07 us per step (+- 0.50)"
