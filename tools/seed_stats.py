"""Statistics over seeds for the schedule comparisons (tools/summarise_*.py): the mean with the
half-width of its two-sided 95% Student-t interval, and its Markdown form."""
import math

# Two-sided 95% quantiles of Student's t by degrees of freedom.
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228}


def mean_ci(xs):
    """(mean, half-width of the 95% interval); the half-width is NaN for fewer than two values."""
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan")
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1))
    return m, T95.get(n - 1, 1.96) * sd / math.sqrt(n)


def fmt(mc, p=3):
    """'mean ± half-width' with p decimals, or the mean alone where there is no interval."""
    return ("%.*f ± %.*f" % (p, mc[0], p, mc[1])) if not math.isnan(mc[1]) else "%.*f" % (p, mc[0])
