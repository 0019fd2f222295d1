//! The introduction of the controller FMU's `documentation/index.html`
//! (the variable table below it is generated from the table).

/// Introduction of the documentation page for an `n`-joint controller.
pub fn documentation_html(n: usize) -> String {
    format!(
        "<p>The EigenMPC controller (Coelho et al., section IV) for a planar chain of {n} \
rigid links (the paper's model: point masses at the link tips): a multiple-shooting NMPC solved \
by real-time iterations that pumps energy into the chain until it oscillates along its nonlinear \
eigenmode at the reference energy <code>E_ref</code>, then lets it swing almost torque-free. \
Inputs are the measured joint angles <code>q[j]</code> and speeds <code>qd[j]</code>; outputs \
the joint torques <code>tau[j]</code> and diagnostics.</p>\
<p><b>Timing.</b> The controller solves at the communication points on its sample grid \
<code>t_start + k sample_period</code> (or at the first communication point after a grid \
point that falls inside a step) and holds the torque in between. A solve at <code>t</code> \
uses the inputs set for <code>t</code>: in initialization mode for the first solve (the \
outputs are valid after <code>fmi2ExitInitializationMode</code>), afterwards the inputs set \
before <code>fmi2DoStep(t, h)</code>; its torque is the output when that call returns. \
Stepping the controller before the plant therefore applies the torque computed from the \
state at <code>t</code> over <code>[t, t + h]</code>. A communication step longer than the \
sample period gets one solve per step and a warning (once).</p>\
<p><b>Model.</b> Per link <code>m[j]</code>, <code>l[j]</code>, the centre-of-mass distance \
<code>r[j]</code> and the inertia about the joint <code>I[j]</code> (negative, the default: a \
point mass at the tip, <code>r = l</code>, <code>I = m r^2</code>); per joint the motor \
(<code>Ir[j]</code>, <code>gr[j]</code>), friction (<code>b[j]</code>, <code>cf[j]</code>) \
and spring (<code>k[j]</code>, <code>q_rest[j]</code>). A non-physical combination is refused \
at <code>fmi2ExitInitializationMode</code> with a message naming the parameter.</p>\
<p><b>Variants.</b> <code>variant</code> = curved needs the chart <code>chart.coef[j,k]</code> \
of the eigenmode at <code>E_ref</code> (default: the in-phase mode of the default model); \
compute other charts with <code>eigenmpc modes --energies E --fmu-start-values FILE</code> \
and load FILE as start values. A negative <code>w_E</code> (the default) selects the paper's \
energy weight of the variant: 25 curved, 5 straight. Below <code>E_scale</code> (default \
14 J, where the paper tuned <code>w_E</code>) the energy residual is scaled by \
<code>sqrt(E_scale / E_ref)</code>, so that a low <code>E_ref</code> is reached about as fast \
as 14 J; from <code>E_scale</code> up, and with <code>E_scale</code> = 0, it is the \
paper's <code>E_ref - E</code>.</p>\
<p><b>solver_status.</b> 0 solved (the first sample too: ten Gauss-Newton iterations from a \
zero-torque guess, bounded work); 1 not converged (not reported by this FMU); 2 QP failed: the torque is the fallback (the previous plan's next control, clipped) \
and a warning is logged. Code 3 (invalid state) belongs to the C API: this FMU refuses NaN/Inf \
inputs with fmi2Error before any solve.</p>\
<p><b>Delay and lag.</b> <code>measurement_delay</code> (s) declares the age of the measured \
state when it arrives: the controller predicts it forward with its model and the torques it \
sent since (the state estimator filters it at its own time). <code>actuator_time_constant</code> \
(s) declares a first-order lag of the motor: integrated exactly over the delay, taken as a dead \
time over the horizon. A declared delay of 4 samples or lag of 2 costs nothing measurable on the \
paper's scenario (docs/delay.md). <code>torque_response</code> declares instead a motor that \
moves per sample by a times the distance to the command (u += a (tau - u), a in (0, 2]): the \
plan's controls are then the applied torques, and tau is the command that makes the motor apply \
the first one (an overshooting motor, 1 &lt; a &lt;= 2, is cancelled exactly).</p>\
<p><b>Refused values.</b> A value out of range (or NaN/Inf) is refused with fmi2Error; the old \
value stays in place and readable, and the instance is in the FMI error state: call \
fmi2Reset to continue.</p>"
    )
}
