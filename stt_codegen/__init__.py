"""stt-codegen: spatiotemporal-tube controllers for prescribed-time reach-avoid-stay tasks.

The method is "Prescribed-time Reach-Avoid-Stay Specifications for Unknown Systems: A
Spatiotemporal Tubes Approach". Main entry points:

* :func:`stt_codegen.spec.loader.load_spec` - read and validate a spec (TOML);
* :func:`stt_codegen.design.search.design_tube` - choose windows, circumvents and gain;
* :func:`stt_codegen.tube.model.build_model` - the CasADi functions of the tube and controller;
* :mod:`stt_codegen.tube.reference` - the numpy reference of eqs. (2)-(13);
* :func:`stt_codegen.runtime.simulate.simulate` - the sampled closed loop and Definition 2.1.
"""

__version__ = "0.1.0"
