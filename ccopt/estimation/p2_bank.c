/* One P² step of many streams (the hot path of ccopt.estimation.quantile.P2QuantileBank; see
 * p2_step.py, which compiles and calls it).
 *
 * A line-for-line transcription of P2Quantile.add past its first five samples and of
 * _adjust_marker and interpolate (quantile.py): the same floating-point operations in the same
 * order, so the heights and positions are those of the Python reference bit for bit, signed zeros
 * too. Build without -ffast-math and with -ffp-contract=off.
 */
#include <math.h>

#define MARKERS 5

/* low + fraction (high - low), or the convex combination where the difference overflows. */
static double interpolate(double low, double high, double fraction) {
    double value = low + fraction * (high - low);
    return isfinite(value) ? value : (1.0 - fraction) * low + fraction * high;
}

/* Move marker one position towards its desired one if it lags by 1 or more and there is room. */
static void adjust_marker(double *heights, double *positions, int marker, double lag) {
    double gap_above = positions[marker + 1] - positions[marker];
    double gap_below = positions[marker] - positions[marker - 1];
    double step;
    if (lag >= 1.0 && gap_above > 1.0) {
        step = 1.0;
    } else if (lag <= -1.0 && gap_below > 1.0) {
        step = -1.0;
    } else {
        return;
    }
    double height = heights[marker], above = heights[marker + 1], below = heights[marker - 1];
    double parabolic = height + step / (gap_above + gap_below) *
                                    ((gap_below + step) * (above - height) / gap_above +
                                     (gap_above - step) * (height - below) / gap_below);
    if (below < parabolic && parabolic < above) {
        heights[marker] = parabolic;
    } else if (step > 0.0) {
        heights[marker] = height + (above - height) / gap_above;
    } else {
        heights[marker] = height - (height - below) / gap_below;
    }
    if (!isfinite(heights[marker])) {
        double neighbour = step > 0.0 ? above : below, gap = step > 0.0 ? gap_above : gap_below;
        heights[marker] = interpolate(height, neighbour, 1.0 / gap);
    }
    positions[marker] += step;
}

/* One sample per stream for streams that have seen five or more: heights and positions
 * (streams x 5, stream by stream) in place, samples (streams), levels (5, the markers'). Returns 1,
 * or 0 and changes nothing where a sample is not finite (P2QuantileBank.add skips such a row). */
int ccopt_p2_bank(int streams, double *heights_all, double *positions_all, const double *samples,
                  const double *levels) {
    for (int i = 0; i < streams; i++) {
        if (!isfinite(samples[i])) return 0;
    }
    for (int i = 0; i < streams; i++) {
        double *heights = heights_all + MARKERS * i, *positions = positions_all + MARKERS * i;
        double sample = samples[i];
        int cell;
        if (sample < heights[0]) {
            heights[0] = sample;
            cell = 0;
        } else if (sample >= heights[4]) {
            heights[4] = sample;
            cell = 3;
        } else if (sample < heights[1]) {
            cell = 0;
        } else if (sample < heights[2]) {
            cell = 1;
        } else if (sample < heights[3]) {
            cell = 2;
        } else {
            cell = 3;
        }
        for (int marker = cell + 1; marker < MARKERS; marker++) positions[marker] += 1.0;
        double top = positions[4];
        for (int marker = 1; marker <= 3; marker++) {
            double lag = top * levels[marker] - positions[marker];
            if (lag >= 1.0 || lag <= -1.0) adjust_marker(heights, positions, marker, lag);
        }
    }
    return 1;
}
