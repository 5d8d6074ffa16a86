"""Batches of jobs over a corpus: a manifest of items (:mod:`.manifest`), what each job kind
runs (:mod:`.jobs`), the done-records that make a rerun skip finished items and the summary
table (:mod:`.records`), and one item run into its own folder (:mod:`.execute`).

The orchestration on dask.distributed is :func:`facemech.workflows.batch.run_batch`.
"""
