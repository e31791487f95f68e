"""Statistics over seeds for the schedule comparisons (tools/summarise_*.py): the mean with the
half-width of its two-sided 95% Student-t interval, and its Markdown form."""
import functools
import math


@functools.lru_cache(maxsize=None)
def t975(nu):
    """The 0.975 quantile of Student's t with nu degrees of freedom (12.706 at 1, 2.776 at 4, 2.093 at
    19): bisection on its distribution function, integrated by Simpson's rule over the density."""
    c = math.exp(math.lgamma((nu + 1) / 2) - math.lgamma(nu / 2)) / math.sqrt(nu * math.pi)
    density = lambda x: c * (1 + x * x / nu) ** (-(nu + 1) / 2)

    def mass(t, n=2000):  # P(0 <= T <= t)
        h = t / n
        return h / 3 * sum((1 if i in (0, n) else 4 if i % 2 else 2) * density(i * h) for i in range(n + 1))

    lo, hi = 0.0, 20.0
    for _ in range(50):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if mass(mid) < 0.475 else (lo, mid)
    return (lo + hi) / 2


def mean_ci(xs):
    """(mean, half-width of the 95% interval); the half-width is NaN for fewer than two values."""
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan")
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1))
    return m, t975(n - 1) * sd / math.sqrt(n)


def fmt(mc, p=3):
    """'mean ± half-width' with p decimals, or the mean alone where there is no interval."""
    return ("%.*f ± %.*f" % (p, mc[0], p, mc[1])) if not math.isnan(mc[1]) else "%.*f" % (p, mc[0])
