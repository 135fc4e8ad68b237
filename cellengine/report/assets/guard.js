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
