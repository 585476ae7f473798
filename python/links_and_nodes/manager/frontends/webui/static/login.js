// The login form: HTTP Basic credentials to POST /login (which sets the session cookie),
// then the page.
const form = document.getElementById('login');
form.addEventListener('submit', async (ev) => {
  ev.preventDefault();
  const user = document.getElementById('user').value;
  const password = document.getElementById('password').value;
  const bytes = new TextEncoder().encode(`${user}:${password}`);
  const basic = btoa(String.fromCharCode(...bytes));
  const answer = await fetch('/login', {method: 'POST', credentials: 'same-origin',
                                        headers: {Authorization: `Basic ${basic}`}});
  if (answer.ok) {
    location.href = '/';
  } else {
    document.getElementById('login-error').textContent =
      answer.status === 401 ? 'wrong user or password' : `login failed (${answer.status})`;
  }
});
