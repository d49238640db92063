"""From a validated scene to the static model the time loop needs (`build.system.build`): the
System, the initial state, the probes, and what `jaxslosh check` says of them."""
