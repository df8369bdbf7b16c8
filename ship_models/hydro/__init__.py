"""Estimation methods for vessel coefficients, one module per job.

- :mod:`.hull`: strip hull (sections S, B, d on Gauss stations), parametric generator
- :mod:`.hydrostatics`: GZ(phi) with free sinkage and trim, sine-series fit
- :mod:`.resistance`: ITTC-1957 + Holtrop & Mennen wave resistance, spline fit
- :mod:`.propeller`: B-series K_T, wake and thrust deduction, n(Fn) closed form
- :mod:`.added_mass`: Söding m_x, Lewis-section strip m_y and J_zz
- :mod:`.manoeuvring`: Inoue et al. hull derivatives, Fujii rudder lift slope
- :mod:`.roll`: roll inertia from T_phi, Ikeda lift damping
- :mod:`.waves`: Froude-Krylov strip forces and slender-body wave lift (ops-traced)
"""
