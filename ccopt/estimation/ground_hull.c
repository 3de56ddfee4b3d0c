/* The ground hull's polygon and friction-face search in C: the hot part of a fit of
 * ccopt.estimation.ground_cone (see ground_hull.py, which compiles and calls it).
 *
 * Each function is a line-for-line transcription of its Python reference in ground_cone.py, the
 * same floating-point operations in the same order, so the polygon and the faces' ends are those
 * of the reference bit for bit. Build without -ffast-math and without contracting a * b + c into
 * a fused multiply-add (-ffp-contract=off): either would change the rounding.
 */
#include <math.h>

/* Whether point (x, y) is strictly outside line k: _outside. */
static int outside(const double *ux, const double *uy, const double *h, int k, double x, double y) {
    return ux[k] * x + uy[k] * y > h[k];
}

/* Where lines i and j meet, NaN where they are parallel: _corner. */
static void corner(const double *ux, const double *uy, const double *h, int i, int j, double *x, double *y) {
    double det = ux[i] * uy[j] - uy[i] * ux[j];
    if (det == 0.0) {
        *x = NAN;
        *y = NAN;
        return;
    }
    *x = (uy[j] * h[i] - uy[i] * h[j]) / det;
    *y = (ux[i] * h[j] - ux[j] * h[i]) / det;
}

/* The half-plane intersection of the lines ux[k] x + uy[k] y = h[k], k = 0 .. count - 1, by
 * ascending angle: _sweep. The deques of lines and corners share one index range: line p and
 * line p + 1 meet at corner p. Writes the active lines and the vertices (vertex i where active
 * lines i and i + 1 meet, cyclically) and returns how many there are. */
static int sweep(int count, const double *ux, const double *uy, const double *h, int *lines, double *xs,
                 double *ys, int *active, double *vx, double *vy) {
    int head = 0, tail = 1; /* lines[head .. tail), corners[head .. tail - 1) */
    lines[0] = 0;
    double top_a = ux[0], top_b = uy[0], top_c = h[0];
    double last_x = NAN, last_y = NAN;
    for (int k = 1; k < count; k++) {
        double a = ux[k], b = uy[k], c = h[k];
        if (a * last_x + b * last_y > c) {
            tail--;
            while (tail - 1 > head) {
                if (!(a * xs[tail - 2] + b * ys[tail - 2] > c)) break;
                tail--;
            }
            int top = lines[tail - 1];
            top_a = ux[top];
            top_b = uy[top];
            top_c = h[top];
        }
        while (tail - 1 > head) {
            if (!(a * xs[head] + b * ys[head] > c)) break;
            head++;
        }
        double det = top_a * b - top_b * a;
        if (det != 0.0) {
            last_x = (b * top_c - top_b * c) / det;
            last_y = (top_a * c - a * top_c) / det;
        } else {
            last_x = NAN;
            last_y = NAN;
        }
        xs[tail - 1] = last_x;
        ys[tail - 1] = last_y;
        lines[tail] = k;
        tail++;
        top_a = a;
        top_b = b;
        top_c = c;
    }
    while (tail - head - 1 >= 2 && outside(ux, uy, h, lines[head], xs[tail - 2], ys[tail - 2])) tail--;
    while (tail - head - 1 >= 2 && outside(ux, uy, h, lines[tail - 1], xs[head], ys[head])) head++;
    corner(ux, uy, h, lines[tail - 1], lines[head], &xs[tail - 1], &ys[tail - 1]);
    int n = tail - head;
    for (int i = 0; i < n; i++) {
        active[i] = lines[head + i];
        vx[i] = xs[head + i];
        vy[i] = ys[head + i];
    }
    return n;
}

static int wrap(int index, int count) {
    int r = index % count;
    return r < 0 ? r + count : r;
}

/* The ends (start x, y, end x, y) of the friction face on the side whose candidate directions are
 * flagged in candidate, as _friction_face finds them before it turns them into a row; returns 0
 * where it finds no seed pair (or a seed chord of zero length), else 1. lengths is scratch. */
static int face_ends(int count, const int *active, const double *vx, const double *vy, const double *ux,
                     const double *uy, const unsigned char *candidate, double window_cosine, double *lengths,
                     double *ends) {
    for (int i = 0; i < count; i++) {
        int p = wrap(i - 1, count);
        lengths[i] = candidate[active[i]] ? hypot(vx[p] - vx[i], vy[p] - vy[i]) : NAN;
    }
    double best = 0.0;
    int first = -1;
    for (int i = 0; i < count; i++) {
        if (!candidate[active[i]]) continue;
        int next = wrap(i + 1, count);
        if (candidate[active[next]] && lengths[i] + lengths[next] > best) {
            best = lengths[i] + lengths[next];
            first = i;
        }
    }
    if (first < 0) return 0;
    int s = wrap(first - 1, count), e = wrap(first + 1, count);
    double length = hypot(vx[e] - vx[s], vy[e] - vy[s]);
    if (length == 0.0) return 0;
    double seed_x = (vy[e] - vy[s]) / length, seed_y = (vx[s] - vx[e]) / length;
    int start = first, end = first + 1;
    while (end - start < count - 1) {
        int k = active[wrap(end + 1, count)];
        if (!(candidate[k] && ux[k] * seed_x + uy[k] * seed_y >= window_cosine)) break;
        end++;
    }
    while (end - start < count - 1) {
        int k = active[wrap(start - 1, count)];
        if (!(candidate[k] && ux[k] * seed_x + uy[k] * seed_y >= window_cosine)) break;
        start--;
    }
    int a = wrap(start - 1, count), b = wrap(end, count);
    ends[0] = vx[a];
    ends[1] = vy[a];
    ends[2] = vx[b];
    ends[3] = vy[b];
    return 1;
}

/* One fit's polygon and faces (_fit_rows up to the rows), for count support directions by
 * ascending angle.
 *
 * inputs: ux, uy (count each), the support values h (count), the prior rows' normals (right x, y,
 * left x, y) and the cosine of the face window. candidates: the candidate flags of the right face,
 * then of the left (count each). work: 5 count doubles, of which the last 2 count receive the
 * polygon's vertices (x, then y). indices: 2 count ints, of which the last count receive the
 * polygon's active lines.
 *
 * Writes out[0] 1 if the support values and the polygon are finite, else 0 (nothing else
 * written); out[1] the number n of active lines; per side s (right 0, left 1) out[2 + 5 s] 1 if a
 * face was found and out[3 + 5 s .. 6 + 5 s] its ends (start x, y, end x, y); out[12], out[13]
 * the prior rows' offsets (the largest projection of a vertex on their normals). Returns n, or 0
 * where out[0] is 0. */
int ccopt_ground_hull(int count, const double *inputs, const unsigned char *candidates, double *work,
                      int *indices, double *out) {
    const double *ux = inputs, *uy = inputs + count, *h = inputs + 2 * count;
    const double *prior_normals = inputs + 3 * count, window_cosine = inputs[3 * count + 4];
    double *xs = work, *ys = work + count, *lengths = work + 2 * count;
    double *vx = work + 3 * count, *vy = work + 4 * count;
    int *active = indices + count;
    out[0] = 0.0;
    for (int k = 0; k < count; k++) {
        if (!isfinite(h[k])) return 0;
    }
    int n = sweep(count, ux, uy, h, indices, xs, ys, active, vx, vy);
    double total = 0.0;
    for (int i = 0; i < n; i++) total += vx[i] + vy[i];
    if (!isfinite(total)) return 0;
    out[0] = 1.0;
    out[1] = (double)n;
    for (int side = 0; side < 2; side++) {
        double *slot = out + 2 + 5 * side;
        slot[0] = (double)face_ends(n, active, vx, vy, ux, uy, candidates + side * count, window_cosine,
                                    lengths, slot + 1);
        double nx = prior_normals[2 * side], ny = prior_normals[2 * side + 1];
        double largest = nx * vx[0] + ny * vy[0];
        for (int i = 1; i < n; i++) {
            double value = nx * vx[i] + ny * vy[i];
            if (value > largest) largest = value;
        }
        out[12 + side] = largest;
    }
    return n;
}
