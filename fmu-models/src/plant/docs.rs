//! The introduction of the plant FMU's `documentation/index.html`.

/// Introduction of the documentation page for an `n`-link plant.
pub fn documentation_html(n: usize) -> String {
    format!(
        "<p>A planar chain of {n} rigid links (by default the EigenMPC paper's model, section \
V: point masses <code>m[j]</code> at the tips of massless links <code>l[j]</code>), \
<code>q[1]</code> the absolute angle of the first link from the downward vertical, \
<code>q[j]</code> the angle of link j relative to link j-1, gravity <code>g</code>. Each link \
may have its centre of mass at <code>r[j]</code> and an inertia <code>I[j]</code> about its \
joint (negative, the default: point mass at the tip); each joint a motor (rotor inertia \
<code>Ir[j]</code> behind a gearbox <code>gr[j]</code>, carried by the previous link), viscous \
friction <code>b[j]</code> (also settable as <code>damping[j]</code>), smooth Coulomb friction \
<code>cf[j] atan(coulomb_sharpness qd[j])</code> and a spring (<code>k[j]</code>, \
<code>q_rest[j]</code>). The inputs are the joint torques <code>tau[j]</code>, held constant \
over a communication step. <code>fmi2DoStep</code> integrates with an adaptive Dormand-Prince \
5(4) method (tolerances <code>rtol</code>, <code>atol</code>; a master's \
<code>fmi2SetupExperiment</code> tolerance sets <code>rtol</code> while that parameter is at its \
start value), so the result does not depend on \
the communication step size; <code>energy</code> is the total mechanical energy (zero at rest \
at the stable equilibrium).</p>"
    )
}
