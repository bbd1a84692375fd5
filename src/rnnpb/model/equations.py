"""The network's equations as every fast path runs them: the units, one step forward and back,
the regression window's passes, the PB update of eqs. 1–2 and the safety barrier's risk
network.

Written once, as plain Python over NumPy arrays, and compiled by numba
(:func:`rnnpb.model._numba.kernel`): the on-line step (:mod:`rnnpb.model.online`) and the
learning iteration (:mod:`rnnpb.model.learning_kernel`) call these functions and nothing else
for the network's arithmetic. Each function works in the precision of the arrays it is given:
float32 is the fast path, float64 the reference the tests hold it to (the constants below are
float32 so that they do not raise a float32 computation to float64). The JAX network of
:mod:`rnnpb.model.network` (generation, the JAX learning chunk) is a separate path; the parity
tests (``tests/model/test_gradients.py``, ``test_learning_kernel.py``) say where the two differ.

A new activation is a change of :func:`unit` and :func:`slope` here (and, for the JAX paths,
of :func:`rnnpb.model.network.step`); a new PB update one of :func:`pb_update`.

Shapes: L steps, G windows run together (sessions, restart profiles, candidates), S sensory,
M motor, P PB, C context, H hidden, IO = S + M + C (a step's outputs; its recurrent inputs).
Arrays of steps are time-major, (L, G, ...), so that the G windows of one step lie together.
"""

from __future__ import annotations

import numpy as np

from rnnpb.model._numba import kernel

F = np.float32
HALF, ONE, TWO = F(0.5), F(1.0), F(2.0)
# tanh(t) ~ t P(t²) / Q(t²) on [-7.9, 7.9] (Eigen's float tanh): within 2e-7 of the exact
# sigmoid, and arithmetic a compiler turns into vector instructions (an exp is a call). The
# native loops (_ir.py) read the same coefficients.
TANH_P = (
    -2.76076847742355e-16,
    2.00018790482477e-13,
    -8.60467152213735e-11,
    5.12229709037114e-08,
    1.48572235717979e-05,
    6.37261928875436e-04,
    4.89352455891786e-03,
)
TANH_Q = (1.19825839466702e-06, 1.18534705686654e-04, 2.26843463243900e-03, 4.89352518554385e-03)
TANH_CLAMP = 7.90531110763549805
_P = tuple(F(c) for c in TANH_P)
_Q = tuple(F(c) for c in TANH_Q)
_CLAMP = F(TANH_CLAMP)


@kernel
def unit(x):
    """The units' activation, the logistic sigmoid ``1 / (1 + exp(-x))``, as
    ``0.5 + 0.5 tanh(x / 2)`` (NaN stays NaN)."""
    t = np.minimum(np.maximum(HALF * x, -_CLAMP), _CLAMP)
    t2 = t * t
    p = (
        (((((_P[0] * t2 + _P[1]) * t2 + _P[2]) * t2 + _P[3]) * t2 + _P[4]) * t2 + _P[5]) * t2
    ) + _P[6]
    q = ((_Q[0] * t2 + _Q[1]) * t2 + _Q[2]) * t2 + _Q[3]
    return HALF + HALF * (t * p / q)


@kernel
def slope(y):
    """The activation's derivative, in terms of its value ``y = unit(x)``."""
    return y * (ONE - y)


@kernel
def tanh(x):
    """tanh, the risk network's units: ``2 unit(2x) - 1``."""
    return TWO * unit(TWO * x) - ONE


@kernel
def accumulate(total, x, w):
    """``total (G, N) += x (G, K) @ w (K, N)``, four inputs at a time: a sum goes to memory
    and back once for four products (the compiler keeps it in memory between inputs)."""
    k_size = w.shape[0]
    whole = k_size - k_size % 4
    for k in range(0, whole, 4):
        for g in range(x.shape[0]):
            a, b, c, d = x[g, k], x[g, k + 1], x[g, k + 2], x[g, k + 3]
            for j in range(w.shape[1]):
                total[g, j] += (a * w[k, j] + b * w[k + 1, j]) + (c * w[k + 2, j] + d * w[k + 3, j])
    for k in range(whole, k_size):
        for g in range(x.shape[0]):
            a = x[g, k]
            for j in range(w.shape[1]):
                total[g, j] += a * w[k, j]


@kernel
def layer_forward(total, x, w, bias):
    """A layer's units ``unit(x @ w + bias)`` of G inputs at once, into ``total (G, N)``."""
    for g in range(total.shape[0]):
        total[g] = bias
    accumulate(total, x, w)
    for g in range(total.shape[0]):
        for j in range(total.shape[1]):
            total[g, j] = unit(total[g, j])


# --- the regression window -------------------------------------------------------------------


@kernel
def window_inputs(net, sensory, seen, motor_sent, n, recorded, fixed, mask, target, target_mask):
    """What a window's passes need of its observations, for one window: ``fixed`` (L, H) the
    hidden layer's input that does not depend on the recurrence or the PB (the seen hands, the
    recorded motor inputs, the bias); ``mask`` (L, IO) which outputs feed back as the next
    step's inputs (sensory where not seen, motor in closed loop, context); ``target`` and
    ``target_mask`` (L, S): the next observation where it is a target of step t's prediction.

    ``seen`` counts only where t < n; ``recorded``: the motor inputs are the commands sent."""
    w_u, w_m = net[0], net[1]
    b_h = net[3]
    length, s = sensory.shape
    m = motor_sent.shape[1]
    for t in range(length):
        fixed[t] = b_h
        for k in range(s):
            observed = seen[t, k] and t < n
            if observed:
                a = sensory[t, k]
                for j in range(fixed.shape[1]):
                    fixed[t, j] += a * w_u[k, j]
            mask[t, k] = F(0.0) if observed else ONE
        for k in range(m):
            if recorded:
                a = motor_sent[t, k]
                for j in range(fixed.shape[1]):
                    fixed[t, j] += a * w_m[k, j]
            mask[t, s + k] = F(0.0) if recorded else ONE
        for k in range(s + m, mask.shape[1]):
            mask[t, k] = ONE
        for k in range(s):
            following = t + 1 < length and t < n - 1 and seen[t + 1, k]
            target_mask[t, k] = ONE if following else F(0.0)
            target[t, k] = sensory[t + 1, k] if following else F(0.0)


@kernel
def first_input(onset_context, onset_motor, first):
    """The window's first input (IO,) from the onset's logits: sensory 0.5 (taken only where
    not seen), the motor and context units."""
    s = first.shape[0] - onset_motor.shape[0] - onset_context.shape[0]
    for k in range(s):
        first[k] = HALF
    for k in range(onset_motor.shape[0]):
        first[s + k] = unit(onset_motor[k])
    for k in range(onset_context.shape[0]):
        first[s + onset_motor.shape[0] + k] = unit(onset_context[k])


@kernel
def window_forward(net, pre, mask, first, rows, hidden, outputs, x):
    """The forward pass of G windows over their first ``rows`` steps (the network of
    :func:`rnnpb.model.network.mixed_loop`): the hidden layer's input is ``pre`` (L, G, H),
    the part that does not depend on the recurrence, plus the last outputs (the first input
    at t = 0) masked by ``mask`` (L, G, IO) times the recurrent weights. Fills ``hidden``
    (L, G, H) and ``outputs`` (L, G, IO); ``x`` (G, IO) is scratch."""
    w_loop, w_out, b_out = net[4], net[5], net[6]
    for t in range(rows):
        for g in range(x.shape[0]):
            for k in range(x.shape[1]):
                previous = first[g, k] if t == 0 else outputs[t - 1, g, k]
                x[g, k] = previous * mask[t, g, k]
        h = hidden[t]
        h[:] = pre[t]
        accumulate(h, x, w_loop)
        for g in range(h.shape[0]):
            for j in range(h.shape[1]):
                h[g, j] = unit(h[g, j])
        layer_forward(outputs[t], h, w_out, b_out)


@kernel
def window_backward(net, hidden, outputs, mask, target, target_mask, rows, d_pre, d_input, grad):
    """The back-propagation of ``0.5 Σ (sensory prediction - next observation)²`` through the
    forward pass of :func:`window_forward`: ``d_pre`` (L, G, H), the error at the hidden
    layer's input of every step, and ``d_input`` (G, IO), the error at the first input (masked
    as it enters). ``grad`` (G, IO) is scratch."""
    w_out_t, w_loop_t = net[7], net[8]
    s = target.shape[2]
    d_input[:] = F(0.0)
    for t in range(rows - 1, -1, -1):
        for g in range(grad.shape[0]):
            for k in range(grad.shape[1]):
                following = mask[t + 1, g, k] if t + 1 < mask.shape[0] else F(0.0)
                d = d_input[g, k] * following
                if k < s:
                    d += (outputs[t, g, k] - target[t, g, k]) * target_mask[t, g, k]
                grad[g, k] = d * slope(outputs[t, g, k])
        dh = d_pre[t]
        dh[:] = F(0.0)
        accumulate(dh, grad, w_out_t)
        for g in range(dh.shape[0]):
            for j in range(dh.shape[1]):
                dh[g, j] *= slope(hidden[t, g, j])
        d_input[:] = F(0.0)
        accumulate(d_input, dh, w_loop_t)
    for g in range(d_input.shape[0]):
        for k in range(d_input.shape[1]):
            d_input[g, k] *= mask[0, g, k]


@kernel
def pb_input(net, fixed, rho, pre):
    """``pre = fixed + unit(rho) @ W_ph`` (L, G, H) for G profiles ``rho`` (G, L, P)."""
    w_p = net[2]
    for t in range(pre.shape[0]):
        for g in range(pre.shape[1]):
            pre[t, g] = fixed[t, g]
            for p in range(w_p.shape[0]):
                a = unit(rho[g, t, p])
                for j in range(w_p.shape[1]):
                    pre[t, g, j] += a * w_p[p, j]


@kernel
def pb_gradient(net, d_pre, rho, rows, g, out):
    """The error's gradient with respect to profile ``g``'s ``rho`` (L, P): the hidden
    layer's input error times W_ph, through the unit; 0 from step ``rows`` on."""
    w_p = net[2]
    out[:] = F(0.0)
    for t in range(rows):
        for p in range(w_p.shape[0]):
            total = F(0.0)
            for j in range(w_p.shape[1]):
                total += d_pre[t, g, j] * w_p[p, j]
            out[t, p] = total * slope(unit(rho[t, p]))


@kernel
def prediction_error(outputs, target, target_mask, g, since):
    """Window ``g``'s sensory prediction error from step ``since`` on: the sum of squares and
    the number of targets."""
    total, count = 0.0, 0
    for t in range(max(since, 0), target.shape[0]):
        for k in range(target.shape[2]):
            if target_mask[t, g, k] != 0:
                e = outputs[t, g, k] - target[t, g, k]
                total += e * e
                count += 1
    return total, count


# --- eqs. 1–2 --------------------------------------------------------------------------------


@kernel
def pb_update(rho, velocity, grad, n, half, k_bp, k_nb, rate, momentum, running, new):
    """One iteration of eqs. 1–2 on the first ``n`` steps of a profile ``rho`` (T, P), in
    place (:mod:`rnnpb.model.parametric_bias`): the error term summed over the integration
    length ``2 half + 1`` (clipped at the ends), the low-pass term with the ends held flat,
    momentum. Steps from ``n`` on keep their values and lose their momentum. ``running``
    (T + 1, P) and ``new`` (T, P) are scratch."""
    length, p_size = rho.shape
    running[0] = F(0.0)
    for t in range(n):
        for p in range(p_size):
            running[t + 1, p] = running[t, p] - grad[t, p]
    for t in range(n):
        upper, lower = min(t + half + 1, n), max(t - half, 0)
        before = max(t - 1, 0)
        after = t + 1 if t + 1 < n else t
        for p in range(p_size):
            summed = running[upper, p] - running[lower, p]
            smooth = rho[after, p] - TWO * rho[t, p] + rho[before, p]
            step = rate * (k_bp * summed + k_nb * smooth) + momentum * velocity[t, p]
            velocity[t, p] = step
            new[t, p] = rho[t, p] + step
    for t in range(n):
        rho[t] = new[t]
    for t in range(n, length):
        velocity[t] = F(0.0)


# --- the safety barrier's risk network (rnnpb.model.meta) ---------------------------------------


@kernel
def risk(meta, rho_row, d_rho):
    """The risk network's logit of the PB ``unit(rho_row)`` (P,) and its gradient with respect
    to ``rho_row``, into ``d_rho`` (P,)."""
    w1, b1, w2, b2, w3, b3 = meta
    r = b1.shape[0]
    h1 = np.empty(r, rho_row.dtype)
    h2 = np.empty(r, rho_row.dtype)
    for j in range(r):
        total = b1[j]
        for p in range(rho_row.shape[0]):
            total += unit(rho_row[p]) * w1[p, j]
        h1[j] = tanh(total)
    logit = b3[0]
    for j in range(r):
        total = b2[j]
        for i in range(r):
            total += h1[i] * w2[i, j]
        h2[j] = tanh(total)
        logit += h2[j] * w3[j]
    for i in range(r):
        total = F(0.0)
        for j in range(r):
            total += w3[j] * (ONE - h2[j] * h2[j]) * w2[i, j]
        h1[i] = total * (ONE - h1[i] * h1[i])
    for p in range(rho_row.shape[0]):
        total = F(0.0)
        for i in range(r):
            total += h1[i] * w1[p, i]
        d_rho[p] = total * slope(unit(rho_row[p]))
    return logit


@kernel
def barrier_gradient(meta, rho, n, span, weight, threshold, grad, d_rho):
    """Adds the barrier's gradient to ``grad`` (L, P): ``weight · softplus(risk logit −
    threshold)`` per step, on the window's newest ``span`` steps (0: all L)."""
    length = rho.shape[0]
    start = 0
    if 0 < span < length:
        start = min(max(n - span, 0), length - span)
    else:
        span = length
    for t in range(start, start + span):
        excess = risk(meta, rho[t], d_rho) - threshold
        factor = weight * unit(excess)
        for p in range(rho.shape[1]):
            grad[t, p] += factor * d_rho[p]


@kernel
def project_out(meta, rho, n, steps, rate, threshold, d_rho):
    """Each of the first ``n`` rows of ``rho`` moved down the risk gradient, at most ``steps``
    steps of ``rate`` (normalized), until its risk logit is below ``threshold``."""
    for t in range(n):
        for _ in range(steps):
            value = risk(meta, rho[t], d_rho)
            if not value > threshold:
                continue
            norm = F(0.0)
            for p in range(rho.shape[1]):
                norm += d_rho[p] * d_rho[p]
            norm = np.sqrt(norm) + F(1e-6)
            for p in range(rho.shape[1]):
                rho[t, p] -= rate * d_rho[p] / norm
