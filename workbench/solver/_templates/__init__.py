"""The templates of the compiled code: real, importable, lintable Python, specialised per model by
:mod:`workbench.solver._compile`.

Each module here compiles and runs on its own against the placeholder hooks
(:mod:`.placeholder_hooks`, dy/dt = -y without events), so that the tests and static tools can
read it. For a model, ``_compile`` writes a copy into the cache directory in which the import
lines tagged ``# @@HOOKS@@`` (and ``@@STEPS@@``, ``@@IMPLICIT@@``, ``@@JACOBIAN@@``,
``@@MODEL_JACOBIAN@@``) name the model's hooks module and the other generated modules instead,
and the lines tagged ``# @@FLAG@@`` get the model's value; the copy's name carries the digest
of its code (``workbench_kernels.kernel_workbench_models_duffing_<digest>``).

==========================  ========================================================
template                    generates, per model
==========================  ========================================================
``integration_loop``        the integration loop (``advance``): start, initial step,
                            choice of method, records, events applied, pauses
``explicit_steps``          one step of DOPRI5, DOP853 or ARK548 and the location of
                            events inside it
``radau_step``              one step of Radau IIA (order 5) with the model's Jacobian
``jacobian``                the model's Jacobian: its analytic hook, else central
                            differences of its ``rhs``
``tangent_hooks``           hooks of the variational system, with saltation at events
``copies_hooks``            hooks of several copies of the model side by side
``placeholder_hooks``       (not generated) the stand-in model of the templates
==========================  ========================================================

``workbench kernel MODEL`` (or :func:`workbench.solver.generated_source`) prints what was
generated for a model.
"""
