"""The stages of the estimation pipeline (:func:`ship_models.estimation.build_vessel_model`).

One module a stage, each filling the coefficients of one group that the vessel file
does not give, by the named method of :mod:`ship_models.hydro`, and recording every
estimate and validity range in the :class:`~.common.Build` it is given:

=====================  ==============================================================
module                 what it does
=====================  ==============================================================
:mod:`.common`         the particulars read once; the record of a build
:mod:`.memo`           the memo of the expensive steps (:func:`.memo.reuse_hydrostatics`)
:mod:`.hull`           which hull the file describes (offsets, mesh or parametric);
                       C_wp, wetted surface, mass
:mod:`.stability`      the watertight topside height and the GZ curve
:mod:`.resistance`     R(u): measured table, MMG R0' or Holtrop & Mennen
:mod:`.propulsion`     K_T(J), w_P, t_P and the propeller
:mod:`.inertia`        added masses m_x, m_y, J_zz; inertias I_zz, I_xx + J_xx
:mod:`.manoeuvring`    hull, heel and rudder derivatives; roll damping
:mod:`.wave_forces`    the wave-force builder and its inputs
=====================  ==============================================================
"""
