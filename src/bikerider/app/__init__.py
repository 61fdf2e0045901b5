"""``bikerider serve``: a local web page for a bicycle's dynamics and the sim-to-real gap diagnosis.

The page is one static HTML/JavaScript file (``static/``, shipped in the package; nothing is
downloaded when it runs) served by the standard library's :class:`http.server.ThreadingHTTPServer`
(:mod:`bikerider.app.server`) with JSON endpoints.  The browser draws every figure itself (SVG);
matplotlib draws only the figures offered for download.  docs/app.md says why.

* :mod:`bikerider.app.bicycle`: a bicycle from a shipped set or an uploaded file, through the
  command line's readers; its parameter table, edits and their errors and notes;
* :mod:`bikerider.app.steer_frame`: the front assembly in the steer-axis frame;
* :mod:`bikerider.app.dynamics`: the computations behind the figures, each run once per input;
* :mod:`bikerider.app.downloads`: parameter files, CSV tables and matplotlib figures;
* :mod:`bikerider.app.uploads`: private upload folders with the command line's size limits;
* :mod:`bikerider.app.gap_jobs`: the gap diagnosis in a background thread;
* :mod:`bikerider.app.server`: the HTTP server and its routes.
"""
