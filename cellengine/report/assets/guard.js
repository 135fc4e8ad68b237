// report.html's first script: catches every error of the page's own script (which runs after
// it) into the DOM (#errors, body[data-status] = 'error'), so a headless browser can read them
// with --dump-dom. The header, up to the blank line, stays out of the page.

(function () {
  function fail(msg) {
    var e = document.getElementById('errors');
    e.hidden = false;
    e.textContent += msg + '\n';
    document.body.dataset.status = 'error';
  }
  window.addEventListener('error', function (ev) {
    fail('error: ' + ev.message + ' (line ' + ev.lineno + ':' + ev.colno + ')');
  });
  window.addEventListener('unhandledrejection', function (ev) {
    fail('unhandled rejection: ' + ev.reason);
  });
  window.ceFail = fail;
})();
