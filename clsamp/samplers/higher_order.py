"""Higher-order digital nets in base 2 by digit interlacing (Dick 2008): ``order=`` of
``sobol`` and base-2 ``digital_net`` (:class:`clsamp.samplers.lowdiscrepancy.DigitalNetB2`).

The net of order alpha in d dimensions is made from a base net in alpha d dimensions:
output digit alpha r + v of dimension j is digit r of base dimension alpha j + v. Interlacing
is linear in the digits, so it is a map of the generating matrices
(:func:`clsamp.generating_matrices.interlace_columns`): the result is again a base-2 digital
net, with 32 output digits, and Sobol's kernel makes its points. A base net of N = 2^m
points keeps all its digits while alpha m <= 32 (m <= 16 for order 2, m <= 10 for order 3);
past that the low base digits are dropped and the error has a floor near 2^-32.

Which randomizations keep the order, and so which ``randomize`` an interlaced net takes:

* ``"xor"``, the random digital shift: the error of a digitally shifted net depends on its
  dual net only, which the shift leaves alone; Dick's bound holds for every shift.
* ``"lms"``, ``"lms+shift"``: Matoušek's L is drawn for each *base* dimension and
  interlaced (kernel ``lms_matrices`` with ``LD_INTERLACE``), so the points are the
  interlacing of a linearly scrambled base net, as in qmcpy's ``DigitalNetB2(alpha=...)``
  and Dick 2011 (who scrambles the base net, then interlaces). An L applied after
  interlacing would mix the digits of different base dimensions and give the variance of
  an order-1 scrambled net (N^-3), which is why it is not offered.
* refused: ``"owen"`` (nested scrambling of the interlaced digits: the same loss) and the
  Cranley-Patterson ``"shift"`` (a shift mod 1 is no digital map: the shifted points are
  no net, and a smooth non-periodic integrand gains edges).

Published rates of the MSE for smooth integrands (the ``"best"`` case, any d, up to
log factors): N^(-2 alpha) with ``"xor"`` (Dick 2008: worst-case error O(N^-alpha (log
N)^(alpha d)) for functions of smoothness alpha), and N^(-2 alpha - 1) with ``"lms+shift"``
(Dick 2011: RMSE O(N^(-alpha - 1/2 + eps)) for scrambled higher-order nets; Owen 2003:
linear scrambling with a digital shift has the variance of nested uniform scrambling).
Unrandomized or ``"lms"`` without the shift: no variance rate.

References
----------
.. [1] J. Dick, "Walsh spaces containing smooth functions and quasi-Monte Carlo rules of
   arbitrary high order", SIAM J. Numer. Anal. 46(3) (2008), 1519-1553.
.. [2] J. Dick, "Higher order scrambled digital nets achieve the optimal rate of the root
   mean square error for smooth integrands", Ann. Statist. 39(3) (2011), 1372-1398.
.. [3] A. B. Owen, "Variance with alternative scramblings of digital nets", ACM TOMACS
   13(4) (2003), 363-378.
.. [4] J. Dick, F. Pillichshammer, *Digital Nets and Sequences*, Cambridge (2010), ch. 15.
"""

from ..errors import InvalidArgumentError
from ..validation import check_int
from .base import Rate

RANDOMIZATIONS = (None, "xor", "lms", "lms+shift")   # those that keep the order
MAX_ORDER = 3


def check_order(order, d, randomize, base_dimensions, source):
    """The interlacing order after checking it against the sampler's other parameters.

    Parameters
    ----------
    order : int
        1 (the base net itself), 2 or 3.
    d : int
        The sampler's dimension.
    randomize : str or None
        The sampler's randomization.
    base_dimensions : int
        The dimensions the base net has (order d must not pass them).
    source : str
        What holds them, for the message.

    Returns
    -------
    int

    Raises
    ------
    InvalidArgumentError
        An order out of range, a randomization that loses the order, too many dimensions.

    Examples
    --------
    >>> check_order(2, 3, "xor", 21201, "the Joe-Kuo table")
    2
    """
    order = check_int(order, "order", minimum=1, maximum=MAX_ORDER)
    if order > 1 and randomize not in RANDOMIZATIONS:
        raise InvalidArgumentError(
            f"'randomize' must be one of {RANDOMIZATIONS} with order={order} (the "
            f"Cranley-Patterson shift and Owen scrambling of the interlaced digits lose the "
            f"higher order), got {randomize!r}")
    if order * d > base_dimensions:
        raise InvalidArgumentError(
            f"'d' must be at most {base_dimensions // order} with order={order}: d = {d} "
            f"interlaces {order * d} dimensions of {source}, which has {base_dimensions}")
    return order


def rate(order, randomize, case):
    """The published rate of the MSE of an interlaced net (see the module).

    Parameters
    ----------
    order : int
        2 or 3.
    randomize : str or None
    case : {"best", "worst", "axis"}

    Returns
    -------
    Rate or None

    Examples
    --------
    >>> rate(2, "xor", "best")
    Rate(exponent=-4.0, source='Dick 2008')
    """
    if case != "best":
        return None
    if randomize == "xor":
        return Rate(-2.0 * order, "Dick 2008")
    if randomize == "lms+shift":
        return Rate(-2.0 * order - 1, "Dick 2011")
    return None
