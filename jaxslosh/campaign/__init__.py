"""Campaigns: a scene's sea template run over a scatter of sea states x headings x seeds on Dask,
with response statistics per case (`jaxslosh campaign`, `js.campaign`)."""
